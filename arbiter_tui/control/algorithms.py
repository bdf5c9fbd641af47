"""Missions (waypoint lists) and the controllers the analytics compare: manual, go_to_goal, pure_pursuit.

A controller maps (pose, mission progress) to a commanded twist. Nothing here
knows about time sources, sockets or the UI: the caller steps it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from arbiter_core.kinematics import (
    DEFAULT_LIMITS,
    Limits,
    Pose,
    clamp,
    distance_error,
    heading_error,
    wrap_angle,
)

from ..analytics.runs import MANUAL

Point = tuple[float, float]


def _square(side: float = 2.0) -> list[Point]:
    return [(side, 0.0), (side, side), (0.0, side), (0.0, 0.0)]


def _figure_eight(a: float = 1.5, n: int = 16) -> list[Point]:
    # Lemniscate of Gerono through the origin, starting along +x.
    pts = []
    for k in range(1, n + 1):
        t = 2.0 * math.pi * k / n
        pts.append((round(a * math.sin(t), 6), round(a * math.sin(t) * math.cos(t), 6)))
    return pts


MISSIONS: dict[str, list[Point]] = {
    "square": _square(),
    "figure_eight": _figure_eight(),
}
ALGORITHMS = (MANUAL, "go_to_goal", "pure_pursuit")


@dataclass
class MissionProgress:
    """Which waypoint is the current goal; advances when the robot is within ``tolerance``."""

    waypoints: list[Point]
    tolerance: float = 0.15
    index: int = 0
    start: Point = (0.0, 0.0)
    laps: int = 0
    loop: bool = False

    @classmethod
    def named(cls, name: str, tolerance: float = 0.15, loop: bool = False) -> MissionProgress:
        if name not in MISSIONS:
            raise ValueError(f"unknown mission {name!r}; choose from {', '.join(MISSIONS)}")
        return cls(list(MISSIONS[name]), tolerance=tolerance, loop=loop)

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

    def update(self, pose: Pose) -> Point:
        """Advance past every waypoint already within tolerance; return the current goal."""
        while not self.done and distance_error(pose, self.goal) <= self.tolerance:
            self.index += 1
            if self.done and self.loop:
                self.laps += 1
                self.start = self.waypoints[-1]
                self.index = 0
                break
        return self.goal


@dataclass
class ManualController:
    """Teleop: the command is whatever the operator holds; the mission only supplies the goal for errors."""

    v: float = 0.0
    w: float = 0.0
    name: str = MANUAL

    def command(self, pose: Pose, mission: MissionProgress) -> tuple[float, float]:
        return self.v, self.w


@dataclass
class GoToGoalController:
    """Proportional control on distance and heading error; slows down while turning towards the goal."""

    k_linear: float = 0.8
    k_angular: float = 2.5
    limits: Limits = field(default_factory=lambda: DEFAULT_LIMITS)
    name: str = "go_to_goal"

    def command(self, pose: Pose, mission: MissionProgress) -> tuple[float, float]:
        if mission.done:
            return 0.0, 0.0
        goal = mission.goal
        e_d = distance_error(pose, goal)
        e_th = heading_error(pose, goal)
        v = min(self.k_linear * e_d, self.limits.max_linear) * max(0.0, math.cos(e_th))
        w = clamp(self.k_angular * e_th, self.limits.max_angular)
        return v, w


@dataclass
class PurePursuitController:
    """Pure pursuit along the segment from the previous waypoint to the current one.

    The target is the point ``lookahead`` metres ahead of the robot's projection
    on the segment (the goal itself when closer); curvature ``2 sin(alpha) / L``. It cruises at the
    speed cap (``limits.max_linear``, the max speed on the control screen or ``--speed``).
    """

    lookahead: float = 0.4
    limits: Limits = field(default_factory=lambda: DEFAULT_LIMITS)
    name: str = "pure_pursuit"

    def target(self, pose: Pose, mission: MissionProgress) -> Point:
        (ax, ay), (bx, by) = mission.previous, mission.goal
        dx, dy = bx - ax, by - ay
        seg = math.hypot(dx, dy)
        if seg < 1e-9:
            return (bx, by)
        ux, uy = dx / seg, dy / seg
        s = max(0.0, min(seg, (pose.x - ax) * ux + (pose.y - ay) * uy))
        s_target = min(seg, s + self.lookahead)
        return (ax + ux * s_target, ay + uy * s_target)

    def command(self, pose: Pose, mission: MissionProgress) -> tuple[float, float]:
        if mission.done:
            return 0.0, 0.0
        tx, ty = self.target(pose, mission)
        dist = math.hypot(tx - pose.x, ty - pose.y)
        if dist < 1e-9:
            return 0.0, 0.0
        alpha = wrap_angle(math.atan2(ty - pose.y, tx - pose.x) - pose.theta)
        if abs(alpha) > math.pi / 2:
            # Target behind: turn in place towards it.
            return 0.0, clamp(2.0 * alpha, self.limits.max_angular)
        ld = max(dist, 1e-3)
        curvature = 2.0 * math.sin(alpha) / ld
        v = self.limits.max_linear
        # Slow down approaching the goal so the tolerance circle is not overshot.
        v = min(v, 0.8 * distance_error(pose, mission.goal) + 0.05)
        w = v * curvature
        if abs(w) > self.limits.max_angular:
            scale = self.limits.max_angular / abs(w)
            v, w = v * scale, w * scale
        return v, w


Controller = ManualController | GoToGoalController | PurePursuitController


def make_controller(name: str, limits: Limits = DEFAULT_LIMITS) -> Controller:
    if name == MANUAL:
        return ManualController()
    if name == "go_to_goal":
        return GoToGoalController(limits=limits)
    if name == "pure_pursuit":
        return PurePursuitController(limits=limits)
    raise ValueError(f"unknown algorithm {name!r}; choose from {', '.join(ALGORITHMS)}")
