"""Analytics of whatever drives the robot: runs and DataPoints from the robot's own topics.

The console's own runs come from the controllers it drives. A robot-side controller (Nav2, a student's
node) leaves only its topics: odometry (pose, measured velocity), the command it sends (``cmd_vel``,
Twist or TwistStamped), its plan (``nav_msgs/Path``) and its goal (``goal_pose``). This module turns
those, in time order, into the same runs and DataPoints the console records, in the same store, so the
nine AnalyticsStats, the tracking metrics, the ranking and the exports treat them as driven runs.

Rules (README, "Grade any controller"):
- a **sample** is taken from odometry at ``rate_hz`` (the console's collection rate), with the latest
  command as ``linearVel``/``angularVel`` (the odometry's measured velocity before any command came);
- a **goal** comes from ``goal_pose`` or from a plan whose last pose is more than ``tolerance_m`` from
  the goal in force (a replanned path to the same goal is the same run: Nav2 replans about once a
  second); a new goal ends the active run as aborted and starts one, with the plan (else the straight
  line from where the robot stands) as its reference path for the cross-track metrics;
- ``distanceError``/``headingError`` are the seed's, to that goal; with no goal yet a sample's errors
  are 0 (as a manual sample's with nothing to resume);
- a run **completes** when the robot is within ``tolerance_m`` of its goal and stopped (|v| below
  ``stopped_v``, |ω| below ``stopped_w``); the data's end leaves it aborted;
- ``latencyMs`` is the stamped command's age when it was received: the receive time (the recorder's or
  the console's clock) minus ``header.stamp`` (the sender's clock), so it holds the transport to the
  receiver and any offset between the two clocks; a plain Twist has none (null, as over a simulated link).

Pure: no I/O, no ROS types. Times are integers of nanoseconds (a bag's log time), one clock.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from arbiter_core.kinematics import Pose, distance_error, heading_error

from .model import DataPoint
from .runs import ABORTED, COMPLETED
from .store import AnalyticsStore
from .tracking import reference_path

Point = tuple[float, float]
MAX_AGE_MS = 60_000.0  # a command "older" than a minute (or from the future) carries another clock's stamp


@dataclass(frozen=True, slots=True)
class ObserveConfig:
    label: str = "observed"  # the DataPoints' ``algorithm``: what drove (e.g. nav2_rpp)
    rate_hz: float = 10.0
    tolerance_m: float = 0.15  # the console's mission tolerance
    stopped_v: float = 0.02  # m/s
    stopped_w: float = 0.05  # rad/s


class Observer:
    """Feeds an :class:`AnalyticsStore` from the robot's topics (see the module doc)."""

    def __init__(self, store: AnalyticsStore, config: ObserveConfig = ObserveConfig()) -> None:
        if not config.rate_hz > 0:
            raise ValueError("rate_hz must be > 0")
        self.store = store
        self.config = config
        self._period_ns = round(1e9 / config.rate_hz)
        self._next_sample_ns: int | None = None
        self._cmd: tuple[float, float] | None = None
        self._cmd_latency_ms: float | None = None
        self._goal: Point | None = None
        self._pose: Pose | None = None
        self._run: int | None = None
        self._run_has_plan = False
        self._pending_goal: Point | None = None  # a goal before any odometry: its run starts at the first
        self._pending_plan: np.ndarray | None = None  # ... with this plan, when one came for it
        self._last_ms = 0.0
        self._gap = False  # the next sample follows a gap (the link was lost)
        self.samples = 0
        self.foreign_stamps = 0  # stamped commands whose stamp is from another clock (no latency taken)

    # -- what the screen shows -------------------------------------------------------------------
    @property
    def current_goal(self) -> Point | None:
        """The goal of the observed run in progress (None: no run)."""
        return self._goal if self._run is not None else None

    @property
    def current_run(self) -> int | None:
        return self._run

    # -- what arrives --------------------------------------------------------------------------
    def wants_odometry(self, t_ns: int) -> bool:
        """Whether an odometry message at ``t_ns`` becomes a sample (a reader may skip decoding it)."""
        return self._next_sample_ns is None or t_ns >= self._next_sample_ns

    def on_odometry(self, t_ns: int, x: float, y: float, theta: float, v: float, w: float) -> None:
        if not self.wants_odometry(t_ns) or not all(map(math.isfinite, (x, y, theta, v, w))):
            return
        pose = Pose(x, y, theta)
        self._pose = pose
        if self._pending_goal is not None:
            goal, plan = self._pending_goal, self._pending_plan
            self._pending_goal = self._pending_plan = None
            if plan is None:
                self._start(t_ns, goal, reference_path((x, y), [goal]), plan=False)
            else:
                self._start(t_ns, goal, plan, plan=True)
        self._next_sample_ns = t_ns + self._period_ns
        t_ms = t_ns / 1e6
        self._last_ms = t_ms
        goal = self._goal
        cmd_v, cmd_w = self._cmd if self._cmd is not None else (v, w)
        point = DataPoint(
            timestamp=float(int(t_ms)),
            x=x,
            y=y,
            theta=theta,
            linearVel=cmd_v,
            angularVel=cmd_w,
            distanceError=0.0 if goal is None else distance_error(pose, goal),
            headingError=0.0 if goal is None else heading_error(pose, goal),
            algorithm=self.config.label,
            latencyMs=self._cmd_latency_ms,
            runId=self._run,
            gap=self._gap,
        )
        if self.store.record(point):
            self.samples += 1
            self._gap = False
        if (
            self._run is not None
            and goal is not None
            and point.distanceError <= self.config.tolerance_m
            and abs(v) < self.config.stopped_v
            and abs(w) < self.config.stopped_w
        ):
            self.store.end_run(COMPLETED, t_ms, point.distanceError)
            self._run = None

    def on_command(self, t_ns: int, v: float, w: float, stamp_ns: int | None = None) -> None:
        if not (math.isfinite(v) and math.isfinite(w)):
            return
        self._cmd = (v, w)
        age_ms = None if stamp_ns is None else (t_ns - stamp_ns) / 1e6
        if age_ms is not None and abs(age_ms) > MAX_AGE_MS:
            self.foreign_stamps += 1  # another clock (use_sim_time): no latency, rather than 1.7e12 ms
            age_ms = None
        self._cmd_latency_ms = None if age_ms is None else round(age_ms, 4)

    def on_plan(self, t_ns: int, points: Sequence[Point]) -> None:
        points = [(float(x), float(y)) for x, y in points if math.isfinite(x) and math.isfinite(y)]
        if not points:
            return  # Nav2 publishes an empty path when planning fails: no new goal
        end = points[-1]
        path = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        goal = self._goal or self._pending_goal
        if goal is not None and math.hypot(end[0] - goal[0], end[1] - goal[1]) <= self.config.tolerance_m:
            # replanned to the same goal: the same run; its first plan is its reference path (the
            # straight line from where it started stood in until the plan came)
            if self._run is None:
                self._pending_plan = path
            elif not self._run_has_plan:
                self.store.set_run_path(path)
                self._run_has_plan = True
            return
        if self._pose is None:  # a plan before any odometry: its run starts at the first
            self._pending_goal, self._pending_plan = end, path
            return
        self._start(t_ns, end, path, plan=True)

    def on_goal(self, t_ns: int, x: float, y: float) -> None:
        if not (math.isfinite(x) and math.isfinite(y)):
            return
        same = self._pending_goal if self._pending_goal is not None else (self._goal if self._run else None)
        if same is not None and math.hypot(x - same[0], y - same[1]) <= 1e-9:
            return  # the goal in force again (a latched topic replayed); after a run ended it is a new run
        if self._pose is None:
            self._pending_goal, self._pending_plan = (x, y), None
            return
        self._start(t_ns, (x, y), reference_path((self._pose.x, self._pose.y), [(x, y)]), plan=False)

    def lost(self) -> None:
        """The data stopped for a while (the link to the robot was lost): the run in progress ends as
        aborted at its last sample, and the next sample follows a gap (no path is counted across it)."""
        self.finish()
        self._gap = True
        self._cmd = None
        self._cmd_latency_ms = None

    def finish(self) -> None:
        """The data ended: a run still going ends as aborted, at the last sample."""
        if self._run is not None:
            final = (
                None if self._pose is None or self._goal is None else distance_error(self._pose, self._goal)
            )
            self.store.end_run(ABORTED, self._last_ms, final)
            self._run = None

    # -- runs ----------------------------------------------------------------------------------
    def _start(self, t_ns: int, goal: Point, path: np.ndarray, plan: bool) -> None:
        t_ms = t_ns / 1e6
        if self._run is not None:
            final = None if self._pose is None else distance_error(self._pose, self._goal or goal)
            self.store.end_run(ABORTED, t_ms, final)
        self._goal = goal
        self._run = self.store.begin_run(
            self.config.label, f"goal ({goal[0]:+.2f}, {goal[1]:+.2f})", t_ms, path
        )
        self._next_sample_ns = None  # the run's first sample is the next odometry
