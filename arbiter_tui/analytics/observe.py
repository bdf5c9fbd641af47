"""Analytics of whatever drives the robot: runs and DataPoints from the robot's own topics.

The console's own runs come from the controllers it drives. A robot-side controller (Nav2, a student's
node) leaves only its topics: odometry (pose, measured velocity), the command it sends (``cmd_vel``,
Twist or TwistStamped), its plan (``nav_msgs/Path``), its goal (``goal_pose``) and, for a controller
behind a ROS action (Nav2's ``navigate_to_pose``), the action's goal status
(``<action>/_action/status``). This module turns those, in time order, into the same runs and
DataPoints the console records, in the same store, so the nine AnalyticsStats, the tracking metrics, the
ranking and the exports treat them as driven runs.

Rules (docs/analytics.md, "Grade any controller"):
- a **sample** is taken from odometry at ``rate_hz`` (the console's collection rate), with the latest
  command as ``linearVel``/``angularVel`` (the odometry's measured velocity before any command came); a
  robot standing still outside any run (no run, the latest command zero or none, the odometry's
  velocity below ``runs.STILL_V``/``STILL_W``) gives one sample, where it stopped, and then none until it
  moves: the console's own rule (``runs.IdleSamples``);
- a **goal** comes from ``goal_pose`` or from a plan whose last pose is more than ``tolerance_m`` from
  the goal in force (a replanned path to the same goal is the same run: Nav2 replans about once a
  second); a new goal ends the active run as aborted and starts one;
- the **reference** a run's samples are measured against (cross-track error) is the plan the controller
  was following when each sample was taken: the latest plan received for the run's goal, as Nav2's
  controller server follows the newest path it is given. A run started by ``goal_pose`` is measured
  against the straight line from where it started until its first plan comes; a goal whose plan never
  comes keeps the straight line; an empty plan (Nav2's failed planning) changes nothing. The run's path
  ratio and time limit are against its **first plan** (the straight line where no plan came);
- ``distanceError``/``headingError`` are the seed's, to that goal; with no goal yet a sample's errors
  are 0 (as a manual sample's with nothing to resume);
- a run **completes** when the robot is within ``tolerance_m`` of its goal and stopped (|v| below
  ``stopped_v``, |ω| below ``stopped_w``);
- a run **ends** (aborted) when its controller stops short of the goal: where the action's status is
  known for the run's goal, when that goal ends (SUCCEEDED: completed; ABORTED or CANCELED: aborted), at
  the status's time; otherwise when the commands have been zero (|v| below ``stopped_v`` and |ω| below
  ``stopped_w``) or silent for ``stalled_s`` after the controller had commanded motion, at the moment
  they stopped (the samples after it leave the run), or ``stalled_s`` after the run began when it never
  commanded motion (with no command recorded, the odometry's measured velocity stands for it). After a
  run ended, a plan to the same goal belongs to no run, unless a new goal came (``goal_pose``, or a new
  action goal on the status topic);
- the data's end leaves a run still going aborted;
- ``latencyMs`` is the stamped command's age when it was received: the receive time (the recorder's or
  the console's clock) minus ``header.stamp`` (the sender's clock), so it holds the transport to the
  receiver and any offset between the two clocks; a plain Twist has none (null, as over a simulated link).

Pure: no I/O, no ROS types. Times are integers of nanoseconds (a bag's log time), one clock.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from arbiter_core.kinematics import Pose, distance_error, heading_error

from .model import DataPoint
from .runs import ABORTED, COMPLETED, IdleSamples
from .store import AnalyticsStore
from .tracking import reference_path

Point = tuple[float, float]
MAX_AGE_MS = 60_000.0  # a command "older" than a minute (or from the future) carries another clock's stamp

# action_msgs/msg/GoalStatus
STATUS_ACCEPTED, STATUS_EXECUTING, STATUS_CANCELING = 1, 2, 3
STATUS_SUCCEEDED, STATUS_CANCELED, STATUS_ABORTED = 4, 5, 6
ACTIVE = frozenset((STATUS_ACCEPTED, STATUS_EXECUTING, STATUS_CANCELING))
ENDS_AS = {STATUS_SUCCEEDED: COMPLETED, STATUS_CANCELED: ABORTED, STATUS_ABORTED: ABORTED}


@dataclass(frozen=True, slots=True)
class ObserveConfig:
    label: str = "observed"  # the DataPoints' ``algorithm``: what drove (e.g. nav2_rpp)
    rate_hz: float = 10.0
    tolerance_m: float = 0.15  # the console's mission tolerance
    stopped_v: float = 0.02  # m/s
    stopped_w: float = 0.05  # rad/s
    # commands zero or silent this long end a run short of its goal: Nav2's progress checker's default
    # movement_time_allowance (a controller that has not moved for 10 s has failed, by Nav2's own rule)
    stalled_s: float = 10.0


class Observer:
    """Feeds an :class:`AnalyticsStore` from the robot's topics (see the module doc)."""

    def __init__(self, store: AnalyticsStore, config: ObserveConfig = ObserveConfig()) -> None:
        if not config.rate_hz > 0:
            raise ValueError("rate_hz must be > 0")
        if not config.stalled_s > 0:
            raise ValueError("stalled_s must be > 0")
        self.store = store
        self.config = config
        self._period_ns = round(1e9 / config.rate_hz)
        self._stalled_ns = round(config.stalled_s * 1e9)
        self._next_sample_ns: int | None = None
        self._cmd: tuple[float, float] | None = None
        self._cmd_latency_ms: float | None = None
        self._moved_ns: int | None = None  # when the latest command that moves the robot came
        self._zero_ns: int | None = None  # when the commands became zero (None while they move)
        self._goal: Point | None = None
        self._pose: Pose | None = None
        self._run: int | None = None
        self._run_ns = 0  # when the active run began
        self._pending_goal: Point | None = None  # a goal before any odometry: its run starts at the first
        self._pending_plans: list[np.ndarray] = []  # ... with its first and latest plan, when they came
        self._action_goal: str | None = None  # the action goal the active run is (its status ends it)
        self._fresh_goal: str | None = None  # an action goal that began while no run was active
        self._finished: set[str] = set()  # action goals seen ended (never adopted again)
        self._last_ms = 0.0
        self._gap = False  # the next sample follows a gap (the link was lost)
        self._idle = IdleSamples()  # a robot standing still outside any run: one sample, then none
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
            pending, plans = self._pending_goal, self._pending_plans
            self._pending_goal, self._pending_plans = None, []
            if not plans:
                self._start(t_ns, pending, reference_path((x, y), [pending]), stand_in=True)
            else:
                self._start(t_ns, pending, plans[0], stand_in=False)
                if len(plans) > 1:
                    self.store.follow_path(plans[-1])
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
        commanding = self._cmd is not None and self._cmd != (0.0, 0.0)
        if self._idle.wanted(self._run is not None, commanding, v, w) and self.store.record(point):
            self.samples += 1
            self._gap = False
        if self._cmd is None:  # no command recorded (yet): the robot's own motion says whether it stopped
            self._motion(t_ns, v, w)
        if self._run is None or goal is None:
            return
        if (
            point.distanceError <= self.config.tolerance_m
            and abs(v) < self.config.stopped_v
            and abs(w) < self.config.stopped_w
        ):
            self._end(COMPLETED, t_ms)
        elif self._action_goal is None and (stopped := self._stopped_ns(t_ns)) is not None:
            self._end(ABORTED, stopped / 1e6, drop_later=True)

    def on_command(self, t_ns: int, v: float, w: float, stamp_ns: int | None = None) -> None:
        if not (math.isfinite(v) and math.isfinite(w)):
            return
        self._cmd = (v, w)
        self._motion(t_ns, v, w)
        age_ms = None if stamp_ns is None else (t_ns - stamp_ns) / 1e6
        if age_ms is not None and abs(age_ms) > MAX_AGE_MS:
            self.foreign_stamps += 1  # another clock (use_sim_time): no latency, rather than 1.7e12 ms
            age_ms = None
        self._cmd_latency_ms = None if age_ms is None else round(age_ms, 4)

    def on_plan(self, t_ns: int, points: Sequence[Point] | np.ndarray) -> None:
        """A plan's positions, (k, 2): a sequence of (x, y) or an array (a reader's, not copied again)."""
        path = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        finite = np.isfinite(path).all(axis=1)
        if not finite.all():
            path = path[finite]
        if not len(path):
            return  # Nav2 publishes an empty path when planning fails: no new goal, the reference stays
        end = (float(path[-1, 0]), float(path[-1, 1]))
        goal = self._pending_goal if self._pending_goal is not None else self._goal
        same = goal is not None and math.hypot(end[0] - goal[0], end[1] - goal[1]) <= self.config.tolerance_m
        if self._pose is None:  # before any odometry: its run starts at the first
            if same:
                self._pending_plans = [*self._pending_plans[:1], path]
            else:
                self._pending_goal, self._pending_plans = end, [path]
            return
        if same and self._run is not None:
            self.store.follow_path(path)  # a replan: the controller follows it from now
        elif not same or self._fresh_goal is not None:
            self._start(t_ns, end, path, stand_in=False)
        # else: a plan to the goal of a run that has ended, with no new goal: no run

    def on_goal(self, t_ns: int, x: float, y: float) -> None:
        if not (math.isfinite(x) and math.isfinite(y)):
            return
        same = (
            self._pending_goal
            if self._pending_goal is not None
            else (self._goal if self._run is not None else None)
        )
        if same is not None and math.hypot(x - same[0], y - same[1]) <= 1e-9:
            return  # the goal in force again (a latched topic replayed); after a run ended it is a new run
        if self._pose is None:
            self._pending_goal, self._pending_plans = (x, y), []
            return
        self._start(t_ns, (x, y), reference_path((self._pose.x, self._pose.y), [(x, y)]), stand_in=True)

    def on_goal_status(self, t_ns: int, statuses: Iterable[tuple[str, int]]) -> None:
        """An action's ``GoalStatusArray``: (goal id, status) of each goal it tracks. The active run's
        action goal ending ends the run with its outcome (see the module doc)."""
        active: list[str] = []
        ended: dict[str, int] = {}
        for goal_id, status in statuses:
            if status in ENDS_AS:
                ended[goal_id] = status
            elif status in ACTIVE and goal_id not in self._finished:
                active.append(goal_id)
        mine = self._action_goal
        self._finished.update(ended)
        if self._fresh_goal in ended:
            self._fresh_goal = None
        if self._run is not None and mine is not None and mine in ended:
            self._end(ENDS_AS[ended[mine]], t_ns / 1e6)
        new = [g for g in active if g != mine]
        if self._run is not None and self._action_goal is None and active:
            self._action_goal = active[-1]
        elif self._run is None and new:
            self._fresh_goal = new[-1]  # the next plan (or goal) starts its run, even to the same goal

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
            self._end(ABORTED, self._last_ms)

    # -- runs ----------------------------------------------------------------------------------
    def _motion(self, t_ns: int, v: float, w: float) -> None:
        """What the controller asks for (its command; before any came, what the odometry measures)."""
        if abs(v) >= self.config.stopped_v or abs(w) >= self.config.stopped_w:
            self._moved_ns, self._zero_ns = t_ns, None
        elif self._zero_ns is None:
            self._zero_ns = t_ns

    def _stopped_ns(self, t_ns: int) -> int | None:
        """When the active run's controller stopped, once it has been stopped for ``stalled_s``; else None.
        Stopped: since its commands became zero, or since its last command when none came after it; a
        controller that never commanded motion since the run began: now, ``stalled_s`` after it began."""
        if self._moved_ns is None or self._moved_ns < self._run_ns:
            return t_ns if t_ns - self._run_ns >= self._stalled_ns else None
        stop = self._zero_ns if self._zero_ns is not None else self._moved_ns
        return stop if t_ns - stop >= self._stalled_ns else None

    def _final_error(self) -> float | None:
        return None if self._pose is None or self._goal is None else distance_error(self._pose, self._goal)

    def _end(self, outcome: str, t_ms: float, drop_later: bool = False) -> None:
        self.store.end_run(outcome, t_ms, self._final_error(), drop_later=drop_later)
        self._run = None
        self._action_goal = None

    def _start(self, t_ns: int, goal: Point, path: np.ndarray, stand_in: bool) -> None:
        if self._run is not None:
            self._end(ABORTED, t_ns / 1e6)
        self._goal = goal
        self._run = self.store.begin_run(
            self.config.label, f"goal ({goal[0]:+.2f}, {goal[1]:+.2f})", t_ns / 1e6, path, stand_in=stand_in
        )
        self._run_ns = t_ns
        self._action_goal, self._fresh_goal = self._fresh_goal, None
        self._next_sample_ns = None  # the run's first sample is the next odometry
