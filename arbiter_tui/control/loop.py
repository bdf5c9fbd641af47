"""The console's control loop: teleop or an autonomous controller -> stamped commands; samples -> the store.

No Textual here: the app calls ``tick_control`` at the repeat rate and
``sample`` at the collection rate, with the current monotonic time.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import replace

from arbiter_core.kinematics import Limits, Pose, clamp_twist, distance_error, heading_error

from ..analytics.store import AnalyticsStore, DataPoint
from ..link.base import Link
from .algorithms import ALGORITHMS, MISSIONS, MissionProgress, make_controller
from .teleop import Teleop

TRAIL_POINTS = 2000
TRAIL_STEP_M = 0.01  # the trail gets a point when the robot has moved this far: standing still adds nothing


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
    ) -> None:
        self.link = link
        self.store = store
        self.teleop = teleop
        self._wall_ms = wall_ms
        self.algorithm = "manual"
        self.mission_name = "square"
        self.mission = MissionProgress.named(self.mission_name)
        self.controller = make_controller(self.algorithm)
        self.running = False  # an autonomous controller is driving
        self.command = (0.0, 0.0)  # the last command sent
        self.unsent = 0  # commands refused by the link (disconnected)
        self.trail: deque[tuple[float, float]] = deque(maxlen=TRAIL_POINTS)
        self.trail_version = 0  # bumped with every trail point: the map redraws only then

    # -- selection ----------------------------------------------------------------------
    def set_algorithm(self, name: str) -> None:
        if name not in ALGORITHMS:
            raise ValueError(f"unknown algorithm {name!r}")
        self.stop()
        self.algorithm = name
        self.controller = make_controller(name)

    def cycle_algorithm(self) -> str:
        self.set_algorithm(ALGORITHMS[(ALGORITHMS.index(self.algorithm) + 1) % len(ALGORITHMS)])
        return self.algorithm

    def cycle_mission(self) -> str:
        names = list(MISSIONS)
        self.stop()
        self.mission_name = names[(names.index(self.mission_name) + 1) % len(names)]
        self.mission = MissionProgress.named(self.mission_name)
        return self.mission_name

    def start_autonomous(self) -> bool:
        """Start the selected controller on the mission from the robot's current pose."""
        if self.algorithm == "manual":
            return False
        pose = self.link.telemetry.snapshot()[0]
        self.mission = MissionProgress.named(self.mission_name)
        # Missions are relative to where the robot stands when they start.
        self.mission.waypoints = [(pose.x + x, pose.y + y) for x, y in self.mission.waypoints]
        self.mission.start = (pose.x, pose.y)
        self.running = True
        return True

    def stop(self) -> None:
        """Stop the robot: teleop and any autonomous run; the next tick sends exactly one zero."""
        self.running = False
        self.teleop.stop()

    # -- ticks ----------------------------------------------------------------------------
    def goal(self) -> tuple[float, float]:
        return self.mission.goal

    def autonomy_limits(self) -> Limits:
        """A controller drives no faster than the max speed and turn shown on the control screen."""
        base = self.teleop.limits
        return replace(
            base,
            max_linear=min(self.teleop.speed, base.max_linear),
            max_angular=min(self.teleop.turn, base.max_angular),
        )

    def add_trail(self, x: float, y: float) -> None:
        """A trail point where the robot is, unless it has not moved ``TRAIL_STEP_M`` since the last."""
        if self.trail and math.hypot(x - self.trail[-1][0], y - self.trail[-1][1]) < TRAIL_STEP_M:
            return
        self.trail.append((x, y))
        self.trail_version += 1

    def tick_control(self, now: float) -> tuple[float, float] | None:
        pose, *_ = self.link.telemetry.snapshot()
        self.add_trail(pose.x, pose.y)
        self.mission.update(pose)
        limits = self.teleop.limits
        if self.running:
            if self.mission.done:
                self.stop()
                cmd = self.teleop.tick(now)
            else:
                limits = self.autonomy_limits()
                self.controller.limits = limits
                cmd = self.controller.command(pose, self.mission)
        else:
            cmd = self.teleop.tick(now)
        if cmd is None:
            return None
        v, w = clamp_twist(*cmd, limits)
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
        """Record one DataPoint if collecting (at the collection rate, driven by the caller)."""
        if not self.store.is_collecting:
            return None
        pose, _v, _w, latency = self.link.telemetry.snapshot()
        goal = self.mission.goal
        point = DataPoint(
            timestamp=float(int(self._wall_ms())),
            x=pose.x,
            y=pose.y,
            theta=pose.theta,
            linearVel=self.command[0],
            angularVel=self.command[1],
            distanceError=distance_error(pose, goal),
            headingError=heading_error(pose, goal),
            algorithm=self.algorithm,
            latencyMs=latency,
        )
        return point if self.store.record(point) else None

    def errors(self, pose: Pose) -> tuple[float, float]:
        goal = self.mission.goal
        return distance_error(pose, goal), heading_error(pose, goal)
