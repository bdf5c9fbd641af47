"""A mission run as one immutable value, shared by the console's control loop and the robot-side
controller (``arbiter-backend --autonomy``): what it drives, how far it got, how it ended.

Every change returns a new value (``advanced``, ``ended``, ``resumed_from``); the phase is an enum, and
the name, the counts and the time a panel prints all come from the one value, so they cannot disagree.
A mission belongs to one *life* of the robot's odometry (``life``: the link's counter, bumped when the
link is lost or the pose jumps further than the robot can drive): the console never resumes a mission
of another life, because its waypoints are in a frame that no longer exists.

Pure: no I/O, no clocks (times are passed in, wall milliseconds).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from enum import Enum

from .controllers import MISSIONS, Point
from .kinematics import Pose, distance_error

TOLERANCE_M = 0.15  # a waypoint is reached within this distance
RESUMED = ", resumed"  # what a resumed run's label ends with


class Phase(str, Enum):
    """Where a mission run is; its outcome once it is not ``RUNNING`` (the runs' outcome strings)."""

    RUNNING = "running"
    COMPLETED = "completed"  # reached its last waypoint
    ABORTED = "aborted"  # stopped before its end: a stop, another mission or controller, a lost link
    OVERRIDDEN = "overridden"  # a movement key took over from the controller

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True, slots=True)
class Mission:
    """One run of a route of waypoints (in the odometry frame) by one controller."""

    name: str  # a named mission ("square") or a goal ("goal (+1.50, -0.50)")
    algorithm: str
    waypoints: tuple[Point, ...]
    start: Point = (0.0, 0.0)  # where the robot stood when it started (or resumed)
    index: int = 0  # the waypoint driven to; len(waypoints) once done
    phase: Phase = Phase.RUNNING
    resumed: bool = False
    started_ms: float = 0.0
    ended_ms: float | None = None
    life: int = 0  # the odometry life it belongs to (module doc)
    tolerance: float = TOLERANCE_M

    def __post_init__(self) -> None:
        if not self.waypoints:
            raise ValueError("a mission needs at least one waypoint")
        if not all(math.isfinite(c) for p in (*self.waypoints, self.start) for c in p):
            raise ValueError("a mission's waypoints must be finite")

    # -- made -----------------------------------------------------------------------------------
    @classmethod
    def named(
        cls, name: str, algorithm: str, pose: Pose | None = None, now_ms: float = 0.0, life: int = 0
    ) -> Mission:
        """The named mission from ``pose`` (missions are relative to where the robot stands when they
        start; None: as defined, from the origin)."""
        if name not in MISSIONS:
            raise ValueError(f"unknown mission {name!r}; choose from {', '.join(MISSIONS)}")
        x0, y0 = (0.0, 0.0) if pose is None else (pose.x, pose.y)
        points = tuple((x0 + x, y0 + y) for x, y in MISSIONS[name])
        return cls(name, algorithm, points, start=(x0, y0), started_ms=now_ms, life=life)

    @classmethod
    def to_goal(
        cls, x: float, y: float, algorithm: str, pose: Pose, now_ms: float = 0.0, life: int = 0
    ) -> Mission:
        """Drive from ``pose`` to the point (x, y)."""
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError("a goal needs finite coordinates")
        name = f"goal ({x:+.2f}, {y:+.2f})"
        return cls(name, algorithm, ((float(x), float(y)),), (pose.x, pose.y), started_ms=now_ms, life=life)

    @classmethod
    def route(cls, waypoints: Sequence[Point], start: Point = (0.0, 0.0), index: int = 0) -> Mission:
        """A bare route (tests and benches that drive a controller by hand)."""
        return cls("route", "", tuple((float(x), float(y)) for x, y in waypoints), start, index)

    # -- read (what the controllers read: the Route protocol) ------------------------------------
    @property
    def done(self) -> bool:
        return self.index >= len(self.waypoints)

    @property
    def goal(self) -> Point:
        """The current goal (the last waypoint once the mission is done)."""
        return self.waypoints[min(self.index, len(self.waypoints) - 1)]

    @property
    def previous(self) -> Point:
        return self.start if self.index == 0 else self.waypoints[min(self.index, len(self.waypoints)) - 1]

    @property
    def running(self) -> bool:
        return self.phase is Phase.RUNNING

    @property
    def resumable(self) -> bool:
        """Stopped before its end: ``g`` can take it up from its current waypoint."""
        return self.phase in (Phase.ABORTED, Phase.OVERRIDDEN) and not self.done

    @property
    def total(self) -> int:
        return len(self.waypoints)

    @property
    def reached(self) -> int:
        """Waypoints reached."""
        return min(self.index, self.total)

    @property
    def label(self) -> str:
        """What the panel and the runs call it: ``square`` or ``square, resumed``."""
        return self.name + RESUMED if self.resumed else self.name

    def time_s(self, now_ms: float | None = None) -> float:
        end = self.ended_ms if self.ended_ms is not None else (self.started_ms if now_ms is None else now_ms)
        return max(0.0, (end - self.started_ms) / 1000.0)

    def summary(self) -> str:
        """``done: 4/4 in 20.7 s`` (completed), ``aborted at 2/4`` (ended before its end), ``2/4``."""
        if self.phase is Phase.COMPLETED:
            return f"done: {self.total}/{self.total} in {self.time_s():.1f} s"
        if self.phase is Phase.RUNNING:
            return f"{self.reached}/{self.total}"
        return f"{self.phase.value} at {self.reached}/{self.total}"

    # -- changed -----------------------------------------------------------------------------------
    def advanced(self, pose: Pose) -> Mission:
        """Past every waypoint already within tolerance of ``pose`` (itself when none)."""
        index = self.index
        while index < len(self.waypoints) and distance_error(pose, self.waypoints[index]) <= self.tolerance:
            index += 1
        return self if index == self.index else replace(self, index=index)

    def ended(self, phase: Phase, now_ms: float) -> Mission:
        """The run ends now with ``phase`` (itself when it is not running)."""
        if self.phase is not Phase.RUNNING or phase is Phase.RUNNING:
            return self
        return replace(self, phase=phase, ended_ms=now_ms)

    def resumed_from(self, pose: Pose, algorithm: str, now_ms: float, life: int) -> Mission:
        """Taken up again from its current waypoint, from where the robot stands (pure pursuit then
        follows the segment from here)."""
        return replace(
            self,
            algorithm=algorithm,
            start=(pose.x, pose.y),
            phase=Phase.RUNNING,
            resumed=True,
            started_ms=now_ms,
            ended_ms=None,
            life=life,
        )

    def status(self) -> dict[str, object]:
        """The robot-side controller's API fields of this run."""
        return {
            "state": self.phase.value,
            "algorithm": self.algorithm,
            "mission": self.name,
            "waypoint": self.reached,
            "waypoints": self.total,
        }
