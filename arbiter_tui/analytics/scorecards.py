"""The scorecards the field publishes, per run and per controller: Nav2's controller benchmark and the
BARN challenge's score. Pure: numpy and the runs' summaries, no I/O. Each formula is defined once, here,
beside its source; a figure whose input is missing is ``None`` with the reason, never 0.

**Nav2's controller benchmark** (navigation2 #3239, ``tools/controller_benchmark/process_data.py``), per
run: success, time to goal, path length, integrated linear and angular jerk (the run's own figures:
``tracking.succeeded``, ``RunSummary.time_s``, the seed's ``totalPathLength``, ``tracking.integrated_jerk``)
and, from a recorded ``sensor_msgs/LaserScan`` in the robot's frame, the obstacle distances. Each scan's
**nearest obstacle** is its smallest range r with ``range_min <= r <= range_max`` (no return in range:
none, and the scan does not count); over the scans taken during the run:

* ``min obstacle`` = the smallest of them;
* ``mean-min obstacle`` = their mean, and its standard deviation ``sqrt(sum (d_i - mean)^2 / n)`` (the
  benchmark's ``np.nanmean``/``np.nanstd`` of the per-iteration minima).

The benchmark reads each iteration's local costmap (lethal cells, from the costmap's centre); a scan is
what a recording of a run holds: its ranges are from the laser, not the robot's centre, and neither
subtracts the footprint. Per controller (every run of one algorithm, whatever its goal), as the
benchmark's table: successes over runs (the success rate); time to goal, path length and the jerks
averaged over the runs that succeeded; min obstacle the smallest of the runs'; mean-min and its standard
deviation the mean of the runs'.

**BARN challenge** score (``run.py`` of the-barn-challenge), per run: ``success * OT / clip(AT, 2 OT,
8 OT)`` with the optimal time ``OT = reference length / 2 m/s`` (here the run's first plan, the reference
its path ratio is against) and the actual time ``AT`` from the first sample 0.1 m or more from where the
run began (the script starts its clock once the robot has moved 0.1 m) to the run's end. Success is the
run's (completed within its time limit: ``tracking``); the challenge's own adds "no collision", which a
recording does not say. Per controller: the mean of its runs' scores.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from arbiter_core import stats as S
from arbiter_core.controllers import MANUAL

from .runs import RunSummary

BARN_SPEED_MPS = 2.0  # the challenge's optimal speed: OT = path length / 2 m/s
BARN_MOVED_M = 0.1  # its clock starts once the robot has moved this far from where it began
Samples = tuple[np.ndarray, np.ndarray, np.ndarray]  # a run's (t ms, x, y) in time order
FIGURES = ("time_to_goal_s", "path_length_m", "linear_jerk", "angular_jerk", "barn")  # beside success


@dataclass(frozen=True, slots=True)
class Figure:
    """A scorecard's figure, or why there is none."""

    value: float | None
    why: str | None = None  # set when value is None

    def text(self, fmt: str = ".6f", unit: str = "") -> str:
        return f"— ({self.why})" if self.value is None else f"{self.value:{fmt}}{unit}"

    def as_dict(self) -> Any:
        return round(self.value, 6) if self.value is not None else {"value": None, "why": self.why}


def missing(why: str) -> Figure:
    return Figure(None, why)


@dataclass(frozen=True, slots=True)
class Scans:
    """The nearest obstacle of each recorded scan (NaN: nothing in range), at its time (ms)."""

    topic: str
    t_ms: np.ndarray
    nearest_m: np.ndarray

    def between(self, start_ms: float, end_ms: float) -> np.ndarray:
        lo = int(np.searchsorted(self.t_ms, start_ms, side="left"))
        hi = int(np.searchsorted(self.t_ms, end_ms, side="right"))
        return self.nearest_m[lo:hi]


def nearest_obstacle(ranges: np.ndarray, range_min: float, range_max: float) -> float:
    """A scan's nearest obstacle: its smallest range within [range_min, range_max]; NaN when none is."""
    r = np.asarray(ranges, dtype=np.float64)
    ok = np.isfinite(r) & (r >= range_min) & (r <= range_max)
    return float(r[ok].min()) if ok.any() else math.nan


@dataclass(frozen=True, slots=True)
class Obstacles:
    min_m: Figure
    mean_min_m: Figure
    std_min_m: Figure
    scans: int = 0

    def as_dict(self) -> dict[str, Any]:
        return {"min_obstacle_m": self.min_m.as_dict(), "mean_min_obstacle_m": self.mean_min_m.as_dict(),
                "std_min_obstacle_m": self.std_min_m.as_dict(), "scans": self.scans}  # fmt: skip


def obstacles_of(nearest_m: np.ndarray) -> Obstacles:
    """The benchmark's three obstacle figures over one run's scans (module doc)."""
    d = np.asarray(nearest_m, dtype=np.float64)
    d = d[np.isfinite(d)]
    if not d.size:
        return no_obstacles("no scan during the run saw anything in range")
    return Obstacles(Figure(S.minimum(d)), Figure(S.mean(d)), Figure(S.pstdev(d)), int(d.size))


def no_obstacles(why: str) -> Obstacles:
    return Obstacles(missing(why), missing(why), missing(why), 0)


def barn_score(success: bool, reference_m: float, actual_s: float) -> float:
    """``success * OT / clip(AT, 2 OT, 8 OT)``, ``OT = reference_m / 2 m/s`` (module doc)."""
    ot = reference_m / BARN_SPEED_MPS
    return float(success) * ot / float(np.clip(actual_s, 2 * ot, 8 * ot))


def barn_actual_s(t_ms: np.ndarray, x: np.ndarray, y: np.ndarray, end_ms: float) -> float | None:
    """From the first sample ``BARN_MOVED_M`` or more from the run's first to ``end_ms``; None if it never
    moved that far."""
    if not len(t_ms):
        return None
    moved = np.flatnonzero(np.hypot(x - x[0], y - y[0]) >= BARN_MOVED_M)
    return None if not moved.size else max(0.0, (end_ms - float(t_ms[moved[0]])) / 1000.0)


@dataclass(frozen=True, slots=True)
class RunCard:
    run: int
    algorithm: str
    success: Figure
    time_to_goal_s: Figure
    path_length_m: Figure
    linear_jerk: Figure
    angular_jerk: Figure
    obstacles: Obstacles
    barn: Figure

    def as_dict(self) -> dict[str, Any]:
        return {f: getattr(self, f).as_dict() for f in ("success", *FIGURES)} | self.obstacles.as_dict()


def reference_m(run: RunSummary) -> float | None:
    """The length of the run's first reference, from what its summary says: travelled / path ratio."""
    t = run.tracking
    if t is None or not t.path_ratio:
        return None
    return run.stats.totalPathLength / t.path_ratio


def run_card(
    run: RunSummary,
    samples: Samples | None,
    obstacles: Obstacles,
) -> RunCard:
    """One run's scorecard. ``samples``: its (t ms, x, y) in time order, all of them (None when the file
    holds only part of the run); ``obstacles``: from the scans taken during it (``obstacles_of``)."""
    t = run.tracking
    if t is None or t.success is None:
        why = "no reference path (manual driving)" if t is None else "not in this file (written before it)"
        success = missing(why)
        lin, ang = missing(why), missing(why)
    else:
        success = Figure(t.success)
        no_jerk = "not in this file (written before it)"
        lin = missing(no_jerk) if t.linear_jerk is None else Figure(t.linear_jerk)
        ang = missing(no_jerk) if t.angular_jerk is None else Figure(t.angular_jerk)
    ok = success.value == 1.0
    time_to_goal = Figure(run.time_s) if ok else missing("the run did not succeed")
    return RunCard(
        run.id, run.algorithm, success, time_to_goal, Figure(run.stats.totalPathLength), lin, ang, obstacles,
        _barn(run, samples, success),
    )  # fmt: skip


def _barn(
    run: RunSummary, samples: tuple[np.ndarray, np.ndarray, np.ndarray] | None, success: Figure
) -> Figure:
    if success.value is None:
        return missing(success.why or "no success figure")
    ref = reference_m(run)
    if ref is None or ref <= 0:
        return missing("no reference path length (the robot did not move, or no reference)")
    if success.value != 1.0:
        return Figure(0.0)  # success * ...: a failed run scores 0 whatever its time
    if samples is None:
        return missing("the file holds only part of the run (its start is needed)")
    end = run.end_ms if run.end_ms is not None else run.last_ms
    actual = None if end is None else barn_actual_s(*samples, end)
    if actual is None:
        return missing(f"the robot never moved {BARN_MOVED_M} m from where the run began")
    return Figure(barn_score(True, ref, actual))


@dataclass(frozen=True, slots=True)
class ControllerCard:
    algorithm: str
    runs: int
    successes: int
    success_rate: Figure
    time_to_goal_s: Figure
    path_length_m: Figure
    linear_jerk: Figure
    angular_jerk: Figure
    obstacles: Obstacles
    barn: Figure
    run_ids: tuple[int, ...] = field(default=())

    def as_dict(self) -> dict[str, Any]:
        head = {"algorithm": self.algorithm, "runs": self.runs, "successes": self.successes}
        figures = {f: getattr(self, f).as_dict() for f in ("success_rate", *FIGURES)}
        return head | figures | self.obstacles.as_dict() | {"run_ids": list(self.run_ids)}


def _mean(figures: Iterable[Figure], none: str) -> Figure:
    known = [f.value for f in figures if f.value is not None]
    return Figure(sum(known) / len(known)) if known else missing(none)


def controller_cards(cards: Sequence[RunCard]) -> list[ControllerCard]:
    """Per controller (algorithm), in first-run order, over every run of it (module doc); manual driving
    is not a controller."""
    groups: dict[str, list[RunCard]] = {}
    for c in cards:
        if c.algorithm != MANUAL:
            groups.setdefault(c.algorithm, []).append(c)
    out = []
    for algorithm, group in groups.items():
        rated = [c for c in group if c.success.value is not None]
        won = [c for c in rated if c.success.value == 1.0]
        no_win = "no run succeeded"
        seen = [c.obstacles for c in group if c.obstacles.min_m.value is not None]
        why_obstacles = next((c.obstacles.min_m.why for c in group), None) or "no scan"
        obstacles = (
            Obstacles(
                Figure(min(o.min_m.value for o in seen if o.min_m.value is not None)),
                _mean((o.mean_min_m for o in seen), why_obstacles),
                _mean((o.std_min_m for o in seen), why_obstacles),
                sum(o.scans for o in seen),
            )
            if seen
            else no_obstacles(why_obstacles)
        )
        out.append(
            ControllerCard(
                algorithm,
                len(group),
                len(won),
                Figure(len(won) / len(rated)) if rated else missing("no run has a success figure"),
                _mean((c.time_to_goal_s for c in won), no_win),
                _mean((c.path_length_m for c in won), no_win),
                _mean((c.linear_jerk for c in won), no_win),
                _mean((c.angular_jerk for c in won), no_win),
                obstacles,
                _mean((c.barn for c in group), "no run has a BARN score"),
                tuple(c.run for c in group),
            )
        )
    return out
