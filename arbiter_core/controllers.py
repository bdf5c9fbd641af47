"""Missions (waypoint lists) and the controllers the analytics compare: manual, go_to_goal, pure_pursuit,
stanley, regulated_pure_pursuit, kanayama.

A controller maps (pose, mission progress) to a commanded twist. Nothing here
knows about time sources, sockets or the UI: the caller steps it. Shared by the console (its control
loop and ``compare``) and the backend (``arbiter-backend --autonomy``, the robot-side behaviour node),
so that both run the same control law.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from .kinematics import (
    DEFAULT_LIMITS,
    Limits,
    Pose,
    clamp,
    distance_error,
    heading_error,
    wrap_angle,
)

MANUAL = "manual"  # the algorithm name of driving by hand (and of its runs)
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


def _slalom(gates: int = 6, spacing: float = 0.8, offset: float = 0.4) -> list[Point]:
    # Gates alternately left and right of the x axis: a 90-degree change of heading at every gate,
    # tighter than the turn cap allows at full speed (0.5 m/s at 1 rad/s is a 0.5 m radius).
    pts = [(spacing * k, offset if k % 2 else -offset) for k in range(1, gates + 1)]
    return [*pts, (spacing * (gates + 1), 0.0)]


def _corner(straight: float = 6.0, after: float = 2.0) -> list[Point]:
    # A long straight (where a controller reaches full speed) and one 90-degree left corner.
    return [(straight, 0.0), (straight, after)]


MISSIONS: dict[str, list[Point]] = {
    "square": _square(),
    "figure_eight": _figure_eight(),
    "slalom": _slalom(),
    "corner": _corner(),
}
ALGORITHMS = (MANUAL, "go_to_goal", "pure_pursuit", "stanley", "regulated_pure_pursuit", "kanayama")
CONTROLLERS = ALGORITHMS[1:]  # the autonomous ones: what ``a`` cycles through after manual
DEFAULT_CONTROLLER = "go_to_goal"  # what drives a goal or mission started while manual is selected


def goal_driver(selected: str) -> str:
    """The controller that drives to a goal when ``selected`` is chosen: itself, or the default for manual."""
    return DEFAULT_CONTROLLER if selected == MANUAL else selected


def choose_controller_hint() -> str:
    """How to pick a controller, naming every one the registry has (for hints on screen)."""
    return f"Select a controller with [b]a[/b] first ({', '.join(CONTROLLERS)})"


class Route(Protocol):
    """What a controller reads of the mission it drives (``arbiter_core.mission.Mission``): the waypoints,
    the one driven to, and the leg from the previous one."""

    @property
    def waypoints(self) -> Sequence[Point]: ...

    @property
    def done(self) -> bool: ...

    @property
    def goal(self) -> Point: ...

    @property
    def previous(self) -> Point: ...


@dataclass
class ManualController:
    """Teleop: the command is whatever the operator holds; the mission only supplies the goal for errors."""

    v: float = 0.0
    w: float = 0.0
    name: str = MANUAL

    def command(self, pose: Pose, mission: Route) -> tuple[float, float]:
        return self.v, self.w


@dataclass
class GoToGoalController:
    """Proportional control on distance and heading error; slows down while turning towards the goal."""

    k_linear: float = 0.8
    k_angular: float = 2.5
    limits: Limits = field(default_factory=lambda: DEFAULT_LIMITS)
    name: str = "go_to_goal"

    def command(self, pose: Pose, mission: Route) -> tuple[float, float]:
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

    def lookahead_now(self) -> float:
        """The lookahead distance for this step (fixed here; the regulated variant grows it with speed)."""
        return self.lookahead

    def target(self, pose: Pose, mission: Route) -> Point:
        a, (bx, by), ux, uy, seg = _segment(mission)
        if seg == 0.0:
            return (bx, by)
        s_target = min(seg, _along(pose, a, ux, uy, seg) + self.lookahead_now())
        return (a[0] + ux * s_target, a[1] + uy * s_target)

    def speed(self, pose: Pose, mission: Route, curvature: float) -> float:
        """The cruise speed, slowed approaching the goal (the regulated variant regulates it more)."""
        return _approach_speed(pose, mission.goal, self.limits)

    def command(self, pose: Pose, mission: Route) -> tuple[float, float]:
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
        curvature = 2.0 * math.sin(alpha) / max(dist, 1e-3)
        v = self.speed(pose, mission, curvature)
        return _capped(v, v * curvature, self.limits)


def _segment(mission: Route) -> tuple[Point, Point, float, float, float]:
    """The leg being driven: from the previous waypoint a to the goal b, its unit direction and length."""
    (ax, ay), (bx, by) = mission.previous, mission.goal
    seg = math.hypot(bx - ax, by - ay)
    if seg < 1e-9:
        return (ax, ay), (bx, by), 1.0, 0.0, 0.0
    return (ax, ay), (bx, by), (bx - ax) / seg, (by - ay) / seg, seg


def _along(pose: Pose, a: Point, ux: float, uy: float, seg: float) -> float:
    """How far along the leg (from a, unit direction u, length seg) the robot's projection lies."""
    return max(0.0, min(seg, (pose.x - a[0]) * ux + (pose.y - a[1]) * uy))


def _approach_speed(pose: Pose, goal: Point, limits: Limits) -> float:
    """The speed cap, slowed approaching the goal so the tolerance circle is not overshot."""
    return min(limits.max_linear, 0.8 * distance_error(pose, goal) + 0.05)


def _capped(v: float, w: float, limits: Limits) -> tuple[float, float]:
    """Within the caps, keeping the curvature w/v when the turn rate is what is too large."""
    v = clamp(v, limits.max_linear)
    if abs(w) > limits.max_angular:
        scale = limits.max_angular / abs(w)
        return v * scale, w * scale
    return v, w


@dataclass
class StanleyController:
    """The Stanley law (Thrun et al., 2006), for a differential drive: steer by the heading error to the
    leg plus ``atan(k e / (v + softening))`` of the cross-track error e, as a turn rate ``k_heading`` x
    that steering angle. Speed: the cap, slowed by the steering angle and near the goal.

    Parameters: ``k`` (1/s) how hard the cross-track error is corrected; ``softening`` (m/s) keeps the
    correction finite at low speed; ``k_heading`` (1/s) turn rate per radian of steering."""

    k: float = 2.0
    softening: float = 0.2
    k_heading: float = 2.5
    limits: Limits = field(default_factory=lambda: DEFAULT_LIMITS)
    name: str = "stanley"

    def command(self, pose: Pose, mission: Route) -> tuple[float, float]:
        if mission.done:
            return 0.0, 0.0
        (ax, ay), goal, ux, uy, seg = _segment(mission)
        if seg == 0.0:
            return GoToGoalController(limits=self.limits).command(pose, mission)
        path_heading = math.atan2(uy, ux)
        cross = (pose.x - ax) * -uy + (pose.y - ay) * ux  # left of the leg: positive
        e_heading = wrap_angle(path_heading - pose.theta)
        if abs(e_heading) > math.pi / 2:  # facing away from the leg: turn in place first
            return 0.0, clamp(self.k_heading * e_heading, self.limits.max_angular)
        v = _approach_speed(pose, goal, self.limits)
        steer = e_heading + math.atan2(-self.k * cross, v + self.softening)
        v *= max(0.2, math.cos(steer))
        return _capped(v, self.k_heading * steer, self.limits)


@dataclass
class RegulatedPurePursuitController(PurePursuitController):
    """Pure pursuit with the speed regulation Nav2's Regulated Pure Pursuit documents: slower on tight
    curvature (``v = v_max x min_radius / radius`` below ``min_radius``) and near the goal
    (``v x distance / approach_distance`` within ``approach_distance``), never below ``min_speed``.
    The lookahead grows with speed (``lookahead_time`` x v, within ``[min_lookahead, max_lookahead]``).

    Parameters: ``min_radius`` (m) below which curvature slows the robot; ``approach_distance`` (m);
    ``min_speed`` (m/s); ``lookahead_time`` (s); ``min_lookahead``/``max_lookahead`` (m)."""

    min_radius: float = 0.9
    approach_distance: float = 0.6
    min_speed: float = 0.05
    lookahead_time: float = 1.2
    min_lookahead: float = 0.25
    max_lookahead: float = 0.8
    name: str = "regulated_pure_pursuit"

    def lookahead_now(self) -> float:
        v_max = self.limits.max_linear
        return min(self.max_lookahead, max(self.min_lookahead, self.lookahead_time * v_max))

    def speed(self, pose: Pose, mission: Route, curvature: float) -> float:
        v = self.limits.max_linear
        radius = 1.0 / abs(curvature) if curvature else math.inf
        if radius < self.min_radius:  # curvature regulation
            v *= radius / self.min_radius
        remaining = distance_error(pose, mission.goal)
        if remaining < self.approach_distance:  # proximity regulation
            v *= remaining / self.approach_distance
        return max(v, self.min_speed)


@dataclass
class KanayamaController:
    """Kanayama's tracking law (Kanayama et al., 1990): track a reference moving along the leg at the
    cruise speed, ``v = v_r cos(e_th) + k_x e_x`` and ``w = w_r + v_r (k_y e_y + k_th sin(e_th))`` with
    the errors in the robot's frame. Chosen because it is provably stable (a Lyapunov function) for
    small errors and corrects lateral error smoothly, unlike the geometric laws above; the reference is
    the point ``lead`` metres ahead of the robot's projection on the leg, so it never runs away.

    Parameters: ``k_x`` (1/s), ``k_y`` (1/m^2), ``k_th`` (1/m) gains; ``lead`` (m)."""

    k_x: float = 1.0
    k_y: float = 6.0
    k_th: float = 3.0
    lead: float = 0.3
    limits: Limits = field(default_factory=lambda: DEFAULT_LIMITS)
    name: str = "kanayama"

    def command(self, pose: Pose, mission: Route) -> tuple[float, float]:
        if mission.done:
            return 0.0, 0.0
        (ax, ay), (bx, by), ux, uy, seg = _segment(mission)
        if seg == 0.0:
            return GoToGoalController(limits=self.limits).command(pose, mission)
        s_ref = min(seg, _along(pose, (ax, ay), ux, uy, seg) + self.lead)
        rx, ry, r_th = ax + ux * s_ref, ay + uy * s_ref, math.atan2(uy, ux)
        if distance_error(pose, (bx, by)) < self.lead:  # the reference has reached the goal: face it
            rx, ry, r_th = bx, by, math.atan2(by - pose.y, bx - pose.x)
        dx, dy = rx - pose.x, ry - pose.y
        c, sn = math.cos(pose.theta), math.sin(pose.theta)
        e_x, e_y = c * dx + sn * dy, -sn * dx + c * dy
        e_th = wrap_angle(r_th - pose.theta)
        if abs(e_th) > math.pi / 2:
            return 0.0, clamp(2.5 * e_th, self.limits.max_angular)
        v_r = _approach_speed(pose, (bx, by), self.limits)
        v = v_r * math.cos(e_th) + self.k_x * e_x
        w = v_r * (self.k_y * e_y + self.k_th * math.sin(e_th))
        return _capped(max(0.0, v), w, self.limits)


Controller = (
    ManualController
    | GoToGoalController
    | PurePursuitController
    | StanleyController
    | RegulatedPurePursuitController
    | KanayamaController
)


def make_controller(name: str, limits: Limits = DEFAULT_LIMITS) -> Controller:
    if name == MANUAL:
        return ManualController()
    if name == "go_to_goal":
        return GoToGoalController(limits=limits)
    if name == "pure_pursuit":
        return PurePursuitController(limits=limits)
    if name == "stanley":
        return StanleyController(limits=limits)
    if name == "regulated_pure_pursuit":
        return RegulatedPurePursuitController(limits=limits)
    if name == "kanayama":
        return KanayamaController(limits=limits)
    raise ValueError(f"unknown algorithm {name!r}; choose from {', '.join(ALGORITHMS)}")
