"""A differential-drive robot: consumes ``/cmd_vel_measured``, publishes ``/odom`` (transport-agnostic).

``tick(now)`` advances the model to ``now`` and returns the odometry message; a
transport calls it at 50 Hz. A command older than ``cmd_timeout`` is replaced by
zero, so the robot stops when commands stop, whatever the tracker does.
"""

from __future__ import annotations

import math
from typing import Any

from .kinematics import DEFAULT_LIMITS, Limits, RobotState, step, yaw_to_quaternion
from .topics import stamp

NODE_NAME = "arbiter_simulator"
RATE_HZ = 50.0
_ZERO_COV = [0.0] * 36


class DiffDriveSimulator:
    def __init__(self, limits: Limits = DEFAULT_LIMITS, cmd_timeout: float = 0.5) -> None:
        self.limits = limits
        self.cmd_timeout = cmd_timeout
        self.state = RobotState()
        self._cmd = (0.0, 0.0)
        self._cmd_time: float | None = None
        self._last_tick: float | None = None

    def on_twist(self, msg: dict[str, Any], now: float) -> None:
        """Take a ``geometry_msgs/Twist`` (or the twist of a TwistStamped) in JSON form."""
        twist = msg["twist"] if "linear" not in msg and isinstance(msg.get("twist"), dict) else msg
        try:
            v = float(twist["linear"]["x"])
            w = float(twist["angular"]["z"])
        except (KeyError, TypeError, ValueError):
            return
        if not (math.isfinite(v) and math.isfinite(w)):
            v, w = 0.0, 0.0
        self._cmd = (v, w)
        self._cmd_time = now

    def command(self, now: float) -> tuple[float, float]:
        if self._cmd_time is None or now - self._cmd_time > self.cmd_timeout:
            return (0.0, 0.0)
        return self._cmd

    def tick(self, now: float, wall_ns: int) -> dict[str, Any]:
        dt = 0.0 if self._last_tick is None else min(max(now - self._last_tick, 0.0), 0.2)
        self._last_tick = now
        v, w = self.command(now)
        self.state = step(self.state, v, w, dt, self.limits)
        return odometry(self.state, wall_ns)

    def reset(self) -> None:
        self.state = RobotState()
        self._cmd = (0.0, 0.0)
        self._cmd_time = None


def odometry(state: RobotState, wall_ns: int) -> dict[str, Any]:
    """``nav_msgs/Odometry`` in rosbridge JSON form."""
    p = state.pose
    return {
        "header": {
            "stamp": stamp(wall_ns),
            "frame_id": "odom",
        },
        "child_frame_id": "base_link",
        "pose": {
            "pose": {"position": {"x": p.x, "y": p.y, "z": 0.0}, "orientation": yaw_to_quaternion(p.theta)},
            "covariance": list(_ZERO_COV),
        },
        "twist": {
            "twist": {
                "linear": {"x": state.v, "y": 0.0, "z": 0.0},
                "angular": {"x": 0.0, "y": 0.0, "z": state.w},
            },
            "covariance": list(_ZERO_COV),
        },
    }
