"""Small builders shared by tests."""

import math
import random

from arbiter_tui.analytics.store import DataPoint


def make_point(
    i: int, algorithm: str = "manual", latency: float | None = 0.3, run: int | None = None
) -> DataPoint:
    return DataPoint(
        timestamp=1_700_000_000_000.0 + 100.0 * i,
        x=math.cos(i / 10.0) * i / 10.0,
        y=math.sin(i / 10.0) * i / 10.0,
        theta=math.atan2(math.sin(i / 7.0), math.cos(i / 7.0)),
        linearVel=0.5 * math.sin(i / 5.0),
        angularVel=-0.3 * math.cos(i / 3.0),
        distanceError=abs(math.sin(i / 4.0)) * 2.0,
        headingError=math.sin(i / 6.0) * 3.0,
        algorithm=algorithm,
        latencyMs=latency,
        runId=run,
    )


def random_points(n: int, seed: int = 0, runs: bool = False) -> list[DataPoint]:
    """``runs``: each point also gets a run id (or none), as exports carry them."""
    rng = random.Random(seed)
    algos = ["manual", "go_to_goal", "pure_pursuit"]
    return [
        make_point(
            i,
            rng.choice(algos),
            rng.choice([None, rng.uniform(0.1, 2.0)]),
            rng.choice([None, 1, 2, 70000]) if runs else None,
        )
        for i in range(n)
    ]
