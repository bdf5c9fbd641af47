"""Headless comparison of control algorithms: every algorithm on every mission, in simulated time.

The console's own control loop drives the client-side simulator (50 Hz) at 10 Hz, and samples
DataPoints at the collection rate, exactly as the live console does, but on a simulated clock: a
figure-eight run that takes 40 s on the robot takes a fraction of a second here. No Textual.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from arbiter_core import stats as S
from arbiter_core.controllers import ALGORITHMS, MANUAL, MISSIONS
from arbiter_core.kinematics import Pose, distance_error
from arbiter_core.linkmodel import LinkModel
from arbiter_core.simulator import RATE_HZ

from ..analytics import ranking
from ..analytics.runs import RunSummary
from ..analytics.store import AnalyticsStats, AnalyticsStore, DataPoint
from ..analytics.tracking import TrackingStats, reference_path, tracking_stats
from ..link.modelled import ModelledLink
from .robot import RobotSession
from .settings import Settings

AUTONOMOUS = tuple(a for a in ALGORITHMS if a != MANUAL)
SIM_HZ = RATE_HZ  # the simulator's own rate (arbiter_core.simulator)
CONTROL_HZ = 10.0
TIME_LIMIT_S = 600.0  # a run that has not finished by then counts as not completed
GAP_MS = 1000.0  # between two runs' time spans in an export
CMD_TIMEOUT_S = 0.5  # the simulated robot's deadman, as the backend's simulator (--cmd-timeout)


class CompareError(ValueError):
    """A name the comparison does not know, said in one line with the valid ones."""


@dataclass(frozen=True)
class RunResult:
    algorithm: str
    mission: str
    completed: bool
    time_s: float
    final_error_m: float  # distance from where the robot stopped to the mission's last waypoint
    max_linear_vel: float  # the largest |v| commanded
    stats: AnalyticsStats
    tracking: TrackingStats  # against the mission's path, from where the robot truly was (``true_pose``)
    points: list[DataPoint] = field(repr=False, compare=False)
    summary: RunSummary | None = field(default=None, repr=False, compare=False)  # as the console keeps it

    def as_dict(self) -> dict[str, Any]:
        return {
            "run": None if self.summary is None else self.summary.id,  # the runId its exported points carry
            "algorithm": self.algorithm,
            "mission": self.mission,
            "completed": self.completed,
            "time_s": round(self.time_s, 3),
            "final_error_m": round(self.final_error_m, 4),
            "max_linear_vel": round(self.max_linear_vel, 4),
            "stats": self.stats.as_dict(),
            "tracking": self.tracking.as_dict(),
        }


class _Clock:
    t = 0.0

    def __call__(self) -> float:
        return self.t


def run_one(
    algorithm: str,
    mission: str,
    speed: float = 0.5,
    turn: float = 1.0,
    collection_rate: float = 10.0,
    run_id: int = 1,
    t0_ms: float = 0.0,
    link_model: LinkModel | None = None,
    seed: int = 0,
    cmd_timeout: float = CMD_TIMEOUT_S,
) -> RunResult:
    """One mission run from the origin, in simulated time starting at ``t0_ms`` (epoch ms, what its
    points' timestamps count from); its points carry ``run_id``. The commands and the odometry cross
    ``link_model`` (``link.modelled``; none: a perfect link; jitter and loss drawn from ``seed``); the
    robot stops when no command has arrived for ``cmd_timeout`` s (its deadman, as on the backend)."""
    clock = _Clock()
    link = ModelledLink(link_model or LinkModel(), clock, seed, cmd_timeout=cmd_timeout)
    store = AnalyticsStore(max_data_points=1_000_000, collection_rate=collection_rate)
    # the console's own engine (RobotSession: mission lifecycle, stop and override, run boundaries),
    # ticked here in simulated time at CONTROL_HZ, with no ceiling on the command rate
    settings = Settings(
        speed=speed, turn=turn, collection_rate=collection_rate, max_points=store.max_data_points,
        repeat_rate=None, live=False, handle_signals=False,
    )  # fmt: skip
    session = RobotSession(settings, link, store, clock, wall_ms=lambda: t0_ms + clock.t * 1000.0)
    loop = session.loop
    session.select_algorithm(algorithm)
    session.select_mission(mission)
    if (why := session.go()) is not None:
        raise CompareError(f"{algorithm} cannot drive {mission}: {why}")
    step = 1.0 / SIM_HZ
    control_every = round(SIM_HZ / CONTROL_HZ)
    sample_every = max(1, round(SIM_HZ / collection_rate))
    path = reference_path(loop.mission.start, loop.mission.waypoints)
    truth: list[tuple[float, float, float, float, float]] = []  # t, true x and y, commanded v and w
    max_v = 0.0
    n = 0
    while loop.running and clock.t < TIME_LIMIT_S:
        n += 1
        clock.t = n * step
        link.step()
        if n % control_every == 0:
            session.tick_control()
            max_v = max(max_v, abs(loop.command[0]))
        if n % sample_every == 0 and (point := session.sample()) is not None and point.runId is not None:
            p = _true_pose(link)  # the run's samples, where the robot truly was
            truth.append((clock.t, p.x, p.y, point.linearVel, point.angularVel))
    completed = loop.mission.done
    pose = _true_pose(link)
    last = loop.mission.waypoints[-1]
    if loop.running:  # out of time
        session.stop("out of time")
    (summary,) = store.runs()
    t, x, y, v, w = np.array(truth, dtype=np.float64).reshape(-1, 5).T
    tracking = tracking_stats(t, x, y, v, w, path, S.path_length(x, y),
                              clock.t if completed else None)  # fmt: skip
    return RunResult(
        algorithm=algorithm,
        mission=mission,
        completed=completed,
        time_s=clock.t,
        final_error_m=distance_error(Pose(pose.x, pose.y, pose.theta), last),
        max_linear_vel=max_v,
        stats=summary.stats,
        tracking=tracking,
        points=[replace(p, runId=run_id) for p in store.points() if p.runId == summary.id],
        summary=replace(summary, id=run_id, tracking=tracking),
    )


def _true_pose(link: ModelledLink) -> Pose:
    """Where the robot is now (the console sees it ``odom_delay`` late)."""
    return link.true_pose


def parse_names(text: str, valid: tuple[str, ...], what: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise CompareError(f"--{what}: give at least one of {', '.join(valid)}")
    for name in names:
        if name not in valid:
            raise CompareError(f"--{what}: unknown {name!r}; choose from {', '.join(valid)}")
    return names


def compare(
    missions: list[str],
    algorithms: list[str],
    speed: float = 0.5,
    turn: float = 1.0,
    t0_ms: float | None = None,
    link_model: LinkModel | None = None,
    seed: int = 0,
    cmd_timeout: float = CMD_TIMEOUT_S,
) -> list[RunResult]:
    """Every algorithm on every mission. Each run has its own time span: the first starts at ``t0_ms``
    (default: now), each next one ``GAP_MS`` after the previous one ended, as if driven one after another."""
    start = time.time_ns() / 1e6 if t0_ms is None else t0_ms
    out = []
    for i, (a, m) in enumerate(((a, m) for m in missions for a in algorithms), 1):
        result = run_one(
            a,
            m,
            speed,
            turn,
            run_id=i,
            t0_ms=start,
            link_model=link_model,
            seed=seed + i,
            cmd_timeout=cmd_timeout,
        )
        out.append(result)
        start += result.time_s * 1000.0 + GAP_MS
    return out


def ranking_of(results: list[RunResult]) -> ranking.Ranking:
    """Per-mission rankings and the overall answer (``ranking.RULE``)."""
    return ranking.rank(results)


MISSION_NAMES = tuple(MISSIONS)
__all__ = ["AUTONOMOUS", "MISSION_NAMES", "CompareError", "RunResult", "compare", "ranking_of"]
