"""The console's control loop: teleop or an autonomous controller -> stamped commands; samples -> the store.

No Textual here: the app calls ``tick_control`` at the repeat rate and
``sample`` at the collection rate, with the current monotonic time.

It also says where runs begin and end (``analytics/runs.py``): ``g`` starts a mission run that ends
completed, aborted (stop, another algorithm or mission, the link lost) or overridden (a movement key);
manual driving is a run from the first movement to ``MANUAL_IDLE_S`` without one.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import replace

from arbiter_core.controllers import ALGORITHMS, MANUAL, MISSIONS, goal_driver, make_controller
from arbiter_core.kinematics import Limits, Pose, clamp_twist, distance_error, heading_error
from arbiter_core.mission import Mission, Phase

from ..analytics.runs import ABORTED, COMPLETED, ENDED, MANUAL_IDLE_S, OVERRIDDEN, IdleSamples
from ..analytics.store import AnalyticsStore, DataPoint
from ..analytics.tracking import reference_path
from ..link.base import CONNECTING, DISCONNECTED, RECONNECTING, STARTING, Link
from . import mission as M
from .mission import MissionState
from .teleop import Teleop

TRAIL_POINTS = 2000
TRAIL_STEP_M = 0.01  # the trail gets a point when the robot has moved this far: standing still adds nothing
BURST = 2.0  # commands the rate ceiling lets through at once (a key press answered between two ticks)
NO_ODOMETRY = frozenset({STARTING, CONNECTING, DISCONNECTED, RECONNECTING})  # link states with no live pose


class RateCeiling:
    """The command rate is a ceiling (--repeat-rate): a token bucket of ``BURST`` commands, refilled at
    ``max_rate`` a second (None: no ceiling). Only moving commands take tokens: a stop always goes out."""

    def __init__(self, max_rate: float | None) -> None:
        self.max_rate = max_rate
        self._tokens = BURST
        self._at: float | None = None
        self.held_back = 0  # moving commands the ceiling did not send

    def take(self, now: float) -> bool:
        if self.max_rate is None:
            return True
        if self._at is not None:
            self._tokens = min(BURST, self._tokens + (now - self._at) * self.max_rate)
        self._at = now
        if self._tokens < 1.0:
            self.held_back += 1
            return False
        self._tokens -= 1.0
        return True


class Trail:
    """Where the robot went, for the map: a point each ``TRAIL_STEP_M`` moved (standing adds nothing);
    ``version`` moves with every point (the map redraws only then)."""

    def __init__(self) -> None:
        self.points: deque[tuple[float, float]] = deque(maxlen=TRAIL_POINTS)
        self.version = 0

    def add(self, x: float, y: float) -> None:
        last = self.points[-1] if self.points else None
        if last is not None and math.hypot(x - last[0], y - last[1]) < TRAIL_STEP_M:
            return
        self.points.append((x, y))
        self.version += 1


class ControlLoop:
    """What the robot is told, and what the analytics record: each control tick asks teleop (a held key)
    or the selected controller (a mission run) for a command and sends it on the link; each sample
    turns the link's odometry into a :class:`DataPoint` for the store. No Textual: the app calls
    :meth:`tick_control` and :meth:`sample` from its timers; tests call them with a fake clock."""

    def __init__(
        self,
        link: Link,
        store: AnalyticsStore,
        teleop: Teleop,
        wall_ms: Callable[[], float] = lambda: time.time_ns() / 1e6,
        max_rate: float | None = None,
    ) -> None:
        self.link = link
        self.store = store
        self.teleop = teleop
        self._wall_ms = wall_ms
        self.state = MissionState()  # the mission's lifecycle, one immutable value (control/mission.py)
        self._manual_at: tuple[float, float] | None = None  # (monotonic, wall ms) of the last manual move
        self.controller = make_controller(self.state.algorithm)
        self.command = (0.0, 0.0)  # the last command sent
        self.unsent = 0  # commands refused by the link (disconnected)
        self.trail = Trail()
        self.ceiling = RateCeiling(max_rate)
        self._idle = IdleSamples()  # one sample of a robot standing still outside a run, then none
        # the odometry life followed (arbiter_core.mission): a new one forgets the missions of the last
        self._telemetry = link.telemetry
        self._life = link.telemetry.life
        self.gap_pending = False  # the next sample follows a gap (link down, odometry stale or reset)
        self.notice: str | None = None  # what ``g`` last has to say beside starting (read and cleared)

    # -- the mission's state, read -------------------------------------------------------
    @property
    def algorithm(self) -> str:
        return self.state.algorithm

    @property
    def mission_name(self) -> str:
        return self.state.selected

    @property
    def mission(self) -> Mission:
        """The run in progress (or the last one); before any, the selected mission from the origin."""
        return self.state.current or self.state.preview()

    @property
    def mission_label(self) -> str:
        c = self.state.current
        shown = c is not None and (c.running or not self.state.acknowledged)
        return c.label if shown and c is not None else self.state.selected

    @property
    def running(self) -> bool:
        return self.state.running

    @property
    def interrupted(self) -> Mission | None:
        return self.state.interrupted

    @property
    def finished(self) -> str | None:
        return self.state.finished

    # -- selection ----------------------------------------------------------------------
    def set_algorithm(self, name: str) -> None:
        if name not in ALGORITHMS:
            raise ValueError(f"unknown algorithm {name!r}; choose from {', '.join(ALGORITHMS)}")
        self.stop()
        self.state = M.selecting_algorithm(self.state, name)
        self.controller = make_controller(name)

    def set_mission(self, name: str) -> None:
        if name not in MISSIONS:
            raise ValueError(f"unknown mission {name!r}; choose from {', '.join(MISSIONS)}")
        self.stop()
        self.state = M.selecting_mission(self.state, name)

    def cycle_mission(self) -> str:
        names = list(MISSIONS)
        self.set_mission(names[(names.index(self.mission_name) + 1) % len(names)])
        return self.mission_name

    def _run(self, mission: Mission) -> None:
        self.stop()
        self.state = M.starting(self.state, mission)
        path = reference_path(mission.start, mission.waypoints[mission.index :])
        self.store.begin_run(self.algorithm, mission.label, mission.started_ms, path)

    def start_autonomous(self) -> bool:
        """Start the selected controller on the named mission, from the robot's current pose."""
        if self.algorithm == MANUAL:
            return False
        pose = self.link.telemetry.snapshot()[0]
        self._run(Mission.named(self.mission_name, self.algorithm, pose, self._wall_ms(), self._life))
        return True

    def plan(self, pose: Pose) -> Mission | None:
        """What ``g`` drives, as the map and the panel show it: the run in progress; else the interrupted
        mission ``g`` resumes; else the selected mission from ``pose``, where ``g`` would start it. None
        when ``g`` would start nothing (manual driving with nothing to resume)."""
        if self.running:
            return self.mission
        if self.interrupted is not None:
            return self.interrupted
        if self.algorithm == MANUAL:
            return None
        return self.state.preview(pose)

    def sample_goal(self, pose: Pose) -> tuple[float, float] | None:
        """What a sample's errors are measured to: the goal the control screen shows (the run's, the
        interrupted mission's that ``g`` resumes, or the selected mission's first from here). None while
        driving manually with nothing to resume: no goal, so the sample's errors are 0 (docs/analytics.md,
        "What a sample's error is measured to")."""
        plan = self.plan(pose)
        return None if plan is None else plan.goal

    def go(self) -> bool:
        """``g``: resume an interrupted mission from its current waypoint (with the selected controller,
        or the one it ran with when manual is selected), else start the named mission afresh. A mission
        forgotten since (a lost link, the odometry reset) is said in ``notice``."""
        self.follow_life()
        forgotten = self.state.forgotten
        interrupted = self.interrupted
        if interrupted is None:
            started = self.start_autonomous()
            if started and forgotten is not None:
                self.notice = (f"{self.mission_label} starts afresh from here: the interrupted mission "
                               f"was forgotten ({forgotten})")  # fmt: skip
            return started
        if self.algorithm == MANUAL:
            self.set_algorithm(interrupted.algorithm)
        pose = self.link.telemetry.snapshot()[0]
        self._run(interrupted.resumed_from(pose, self.algorithm, self._wall_ms(), self._life))
        return True

    def restart(self) -> bool:
        """Start the named mission from its first waypoint (an interrupted one is forgotten)."""
        if self.algorithm == MANUAL and self.interrupted is not None:
            self.set_algorithm(self.interrupted.algorithm)
        self.state = M.forgetting_interrupted(self.state)
        return self.start_autonomous()

    def go_to(self, x: float, y: float) -> None:
        """Drive to the point (x, y) in the odometry frame with :func:`goal_driver` of the selection."""
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError("a goal needs finite coordinates")
        self.set_algorithm(goal_driver(self.algorithm))  # the selected controller, else the default
        pose = self.link.telemetry.snapshot()[0]
        self._run(Mission.to_goal(x, y, self.algorithm, pose, self._wall_ms(), self._life))

    def stop(self, outcome: str = ABORTED) -> None:
        """Stop the robot: teleop and any autonomous run; the next tick sends exactly one zero."""
        if self.running:
            now = self._wall_ms()
            self.state = M.stopping(self.state, Phase(outcome), now)
            self.store.end_run(outcome, now, self._final_error())
        self._end_manual_run()
        self.teleop.stop()

    def follow_life(self) -> bool:
        """The link's odometry began a new life (the link was lost, or the pose jumped further than the
        robot can drive: a backend restarted, an odometry reset): a run in progress stops, and nothing is
        left to resume, since its waypoints are in a frame that no longer exists. The next sample follows
        a gap. True when that happened now."""
        telemetry = self.link.telemetry
        if telemetry is not self._telemetry:  # another link attached: its life is the one to follow
            self._telemetry, self._life = telemetry, telemetry.life
            return False
        life, why = telemetry.life, telemetry.life_reason
        if life == self._life:
            return False
        self._life = life
        self.gap_pending = True
        if self.running:
            self.stop()
        self._end_manual_run()
        self.teleop.stop()
        self.state = M.forgetting_interrupted(self.state, why)
        return True

    def acknowledge(self) -> None:
        """A key was pressed: the last run's "done" line goes (it stays until the next run or key)."""
        self.state = M.acknowledged(self.state)

    def override(self) -> None:
        """A movement key takes over from the controller: the run ends as overridden, manual selected."""
        self.stop(OVERRIDDEN)
        self.set_algorithm(MANUAL)

    def _final_error(self) -> float:
        pose = self.link.telemetry.snapshot()[0]
        return distance_error(pose, self.mission.waypoints[-1])

    def _end_manual_run(self) -> None:
        if self._manual_at is not None:
            self.store.end_run(ENDED, self._manual_at[1])
            self._manual_at = None

    def _track_manual(self, now: float, v: float, w: float) -> None:
        """Manual driving is a run from its first movement until ``MANUAL_IDLE_S`` without one."""
        if self.algorithm == MANUAL and (v, w) != (0.0, 0.0):
            if self._manual_at is None:
                self.store.begin_run(MANUAL, "", self._wall_ms())
            self._manual_at = (now, self._wall_ms())
        elif self._manual_at is not None and now - self._manual_at[0] >= MANUAL_IDLE_S:
            self._end_manual_run()

    # -- ticks ----------------------------------------------------------------------------
    def autonomy_limits(self) -> Limits:
        """A controller drives no faster than the max speed and turn shown on the control screen."""
        base = self.teleop.limits
        return replace(
            base,
            max_linear=min(self.teleop.speed, base.max_linear),
            max_angular=min(self.teleop.turn, base.max_angular),
        )

    def tick_control(self, now: float) -> tuple[float, float] | None:
        completed: list[tuple[float, float | None]] = []  # a run that completed at this tick
        try:
            return self._tick(now, completed)
        finally:
            # The run's summary (cross-track figures over all its samples) is made after the stop
            # command left, never before it: it took milliseconds on the command path.
            for t_ms, final_error in completed:
                self.store.end_run(COMPLETED, t_ms, final_error)

    def _tick(self, now: float, completed: list[tuple[float, float | None]]) -> tuple[float, float] | None:
        self.follow_life()
        pose, *_ = self.link.telemetry.snapshot()
        self.trail.add(pose.x, pose.y)
        self.state = M.advancing(self.state, pose)
        limits = self.teleop.limits
        if self.running:
            if self.mission.done:
                t_ms = self._wall_ms()
                self.state = M.completing(self.state, t_ms)
                completed.append((t_ms, self._final_error()))
                self.teleop.stop()
                cmd = self.teleop.tick(now)
            else:
                limits = self.autonomy_limits()
                self.controller.limits = limits  # type: ignore[union-attr]  # a run is never manual's
                cmd = self.controller.command(pose, self.mission)
        else:
            cmd = self.teleop.tick(now)
        if cmd is None:
            self._track_manual(now, 0.0, 0.0)
            return None
        v, w = clamp_twist(*cmd, limits)
        self._track_manual(now, v, w)
        if (v, w) != (0.0, 0.0) and not self.ceiling.take(now):
            return None
        if self.link.send(v, w):
            self.command = (v, w)
        else:
            # The link is down: forget the held key and any autonomous run, so that nothing
            # moves after a reconnect until the user presses a key again. (A refused zero is
            # just dropped: the link sends a zero before the first command after a reconnect.)
            self.unsent += 1
            self.command = (0.0, 0.0)
            if (v, w) != (0.0, 0.0):
                self.stop()
        return (v, w)

    def sample(self) -> DataPoint | None:
        """Record one DataPoint if collecting (at the collection rate, driven by the caller).

        A sample joins the active run while a controller drives, or while a manual key moves the robot.
        A robot standing still outside every run is sampled once, where it stopped, and then not again
        until it moves (``runs.IdleSamples``, observe mode's rule too): idle time never pushes run
        samples out of the ring buffer, and adds nothing to any statistic."""
        if not self.store.is_collecting:
            return None
        self.follow_life()
        if self.link.state in NO_ODOMETRY or not self.link.telemetry.odometry_live(time.monotonic()):
            # no sample of a pose that is not live: the record has a gap here, never the last pose
            # repeated (docs/analytics.md, "A record that never lies")
            self.gap_pending = True
            return None
        pose, v_odom, w_odom, latency = self.link.telemetry.snapshot()
        goal = self.sample_goal(pose)
        run = self.store.active_run
        if run is not None and not self.running and self.command == (0.0, 0.0):
            run = None
        commanding = self.running or self.command != (0.0, 0.0)
        if not self._idle.wanted(run is not None, commanding, v_odom, w_odom):
            return None
        point = DataPoint(
            timestamp=float(int(self._wall_ms())),
            x=pose.x,
            y=pose.y,
            theta=pose.theta,
            linearVel=self.command[0],
            angularVel=self.command[1],
            distanceError=0.0 if goal is None else distance_error(pose, goal),
            headingError=0.0 if goal is None else heading_error(pose, goal),
            algorithm=self.algorithm,
            latencyMs=latency,
            runId=run,
            gap=self.gap_pending,
        )
        if not self.store.record(point):
            return None
        self.gap_pending = False
        return point
