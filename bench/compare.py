"""How long a latency sweep of ``arbiter-tui compare`` takes, and what each controller costs per step.

A sweep is every autonomous controller x every mission x 5 one-way latencies (0, 50, 100, 200, 300 ms,
jitter 10 ms) x 10 trials, each run in simulated time behind the modelled link, exactly as
``arbiter-tui compare --latency 0,50,100,200,300 --jitter 10 --trials 10`` runs it (``run_sweep``:
the runs, their tracking metrics, the trials' intervals and verdicts); timed ``--repeat`` times, the
median reported (target: under 20 s on one core). Per step: one controller's
``command(pose, mission)`` at a pose beside the square's first leg, median of 7 timings of 20,000 calls.

    python bench/compare.py
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

from _common import emit

from arbiter_core.controllers import make_controller
from arbiter_core.kinematics import Pose
from arbiter_core.linkmodel import LinkModel
from arbiter_core.mission import Mission
from arbiter_tui.commands.compare import Sweep, run_sweep
from arbiter_tui.session.compare import AUTONOMOUS, MISSION_NAMES

LATENCIES_MS = (0, 50, 100, 200, 300)


def sweep(trials: int) -> int:
    links = [LinkModel(latency_s=ms / 1e3, jitter_s=0.01) for ms in LATENCIES_MS]
    cells = run_sweep(Sweep(list(MISSION_NAMES), list(AUTONOMOUS), 0.5, 1.0, links, seed=0, trials=trials))
    return sum(len(trial) for cell in cells for trial in cell.runs)


def step_cost_us(name: str, calls: int = 20_000) -> float:
    controller = make_controller(name)
    mission = Mission.named("square", name)
    pose = Pose(0.8, 0.12, 0.1)
    timings = []
    for _ in range(7):
        t0 = time.perf_counter()
        for _ in range(calls):
            controller.command(pose, mission)
        timings.append((time.perf_counter() - t0) / calls * 1e6)
    return statistics.median(timings)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    times, runs = [], 0
    for _ in range(args.repeat):
        t0 = time.process_time()  # CPU time of this one process: one core
        runs = sweep(args.trials)
        times.append(time.process_time() - t0)
    emit(
        {
            "bench": "compare",
            "runs_per_sweep": runs,
            "missions": list(MISSION_NAMES),
            "latencies_ms": list(LATENCIES_MS),
            "trials": args.trials,
            "sweep_cpu_s_median": round(statistics.median(times), 3),
            "sweep_cpu_s_all": [round(t, 3) for t in times],
            "per_run_ms": round(statistics.median(times) / runs * 1e3, 2),
            "controller_step_us": {name: round(step_cost_us(name), 2) for name in AUTONOMOUS},
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
