"""Differential-drive (unicycle) kinematics with velocity and acceleration limits, and tracking errors."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Limits:
    max_linear: float = 1.0  # m/s
    max_angular: float = 2.0  # rad/s
    max_linear_accel: float = 2.0  # m/s^2
    max_angular_accel: float = 6.0  # rad/s^2


DEFAULT_LIMITS = Limits()


@dataclass(frozen=True)
class Pose:
    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0


@dataclass(frozen=True)
class RobotState:
    pose: Pose = Pose()
    v: float = 0.0  # actual linear velocity (m/s)
    w: float = 0.0  # actual angular velocity (rad/s)


def wrap_angle(a: float) -> float:
    """Wrap an angle to [-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


def clamp(value: float, limit: float) -> float:
    """Clamp to [-limit, limit]; any non-finite value becomes 0 (a safe stop)."""
    if not math.isfinite(value):
        return 0.0
    return max(-limit, min(limit, value))


def clamp_twist(v: float, w: float, limits: Limits = DEFAULT_LIMITS) -> tuple[float, float]:
    return clamp(v, limits.max_linear), clamp(w, limits.max_angular)


def _approach(current: float, target: float, max_delta: float) -> float:
    if target > current:
        return min(target, current + max_delta)
    return max(target, current - max_delta)


def limit_speedup(current: float, target: float, max_accel: float, dt: float) -> float:
    """The next commanded velocity on the way from ``current`` to ``target``.

    Speeding up (away from zero) is limited to ``max_accel * dt``; slowing down, towards
    or through zero, is never delayed: the part down to zero happens at once and only the
    part beyond zero in the other direction is rate-limited. A non-finite target is a stop.
    """
    if not math.isfinite(target):
        return 0.0
    if not math.isfinite(current):
        current = 0.0
    if current * target < 0:  # reversing: stop at once, then speed up from rest
        current = 0.0
    if abs(target) <= abs(current):
        return target
    return _approach(current, target, max(0.0, max_accel * dt))


def step(
    state: RobotState, cmd_v: float, cmd_w: float, dt: float, limits: Limits = DEFAULT_LIMITS
) -> RobotState:
    """Advance the robot by ``dt`` seconds towards the commanded twist.

    The command is clamped to the velocity limits, the actual velocities move
    towards it no faster than the acceleration limits allow, and the pose is
    integrated exactly along the resulting arc.
    """
    if dt <= 0:
        return state
    tv, tw = clamp_twist(cmd_v, cmd_w, limits)
    v = _approach(state.v, tv, limits.max_linear_accel * dt)
    w = _approach(state.w, tw, limits.max_angular_accel * dt)
    p = state.pose
    if abs(w) < 1e-9:
        x = p.x + v * dt * math.cos(p.theta)
        y = p.y + v * dt * math.sin(p.theta)
        theta = p.theta
    else:
        theta = p.theta + w * dt
        r = v / w
        x = p.x + r * (math.sin(theta) - math.sin(p.theta))
        y = p.y - r * (math.cos(theta) - math.cos(p.theta))
    return RobotState(Pose(x, y, wrap_angle(theta)), v, w)


JUMP_SLACK_M = 0.25  # odometry jitter and a late message: a step up to this much more is no jump


def odometry_jumped(
    before: Pose, after: Pose, dt_s: float, max_speed: float = DEFAULT_LIMITS.max_linear
) -> bool:
    """A step between two odometry poses ``dt_s`` apart that the robot cannot have driven: farther than
    twice its top speed for that time, plus ``JUMP_SLACK_M``. What a restarted odometry (a backend or a
    driver restarted: back to the origin) or a reset looks like from outside."""
    step = math.hypot(after.x - before.x, after.y - before.y)
    return step > 2.0 * max_speed * max(dt_s, 0.0) + JUMP_SLACK_M


def distance_error(pose: Pose, goal: tuple[float, float]) -> float:
    """Euclidean distance from the robot to the goal (m)."""
    return math.hypot(goal[0] - pose.x, goal[1] - pose.y)


def heading_error(pose: Pose, goal: tuple[float, float]) -> float:
    """Bearing to the goal minus the heading, wrapped to [-pi, pi] (rad)."""
    bearing = math.atan2(goal[1] - pose.y, goal[0] - pose.x)
    return wrap_angle(bearing - pose.theta)


def yaw_to_quaternion(yaw: float) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2.0), "w": math.cos(yaw / 2.0)}


def quaternion_to_yaw(q: dict[str, float]) -> float:
    x, y, z, w = q.get("x", 0.0), q.get("y", 0.0), q.get("z", 0.0), q.get("w", 1.0)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def pose_of_odometry(msg: dict[str, Any]) -> Pose:
    """The pose of a ``nav_msgs/Odometry`` in rosbridge JSON form; KeyError, TypeError or ValueError when
    it has none."""
    p = msg["pose"]["pose"]
    return Pose(float(p["position"]["x"]), float(p["position"]["y"]), quaternion_to_yaw(p["orientation"]))
