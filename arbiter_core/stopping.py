"""What a stop asks of a foreign controller behind a ROS action, and what its answer means. Pure.

One definition for the single-robot console's stop (``arbiter_tui.control.stop``, through rosbridge) and
the robot's own answer to a fleet console's stop (``arbiter_backend.fleet``, in the backend's process):
which actions are cancelled (Nav2's by default), the request that cancels every goal of one
(``action_msgs/srv/CancelGoal`` with a zero goal id and stamp on ``<action>/_action/cancel_goal``), how
long an answer is waited for, and the zero velocity that follows.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum

# Nav2's actions that move the robot (its navigator, controller and behavior servers)
NAV2_ACTIONS = (
    "navigate_to_pose", "navigate_through_poses", "follow_waypoints", "follow_path",
    "spin", "backup", "drive_on_heading", "assisted_teleop",
)  # fmt: skip
CANCEL_TYPE = "action_msgs/srv/CancelGoal"
CANCEL_SUFFIX = "/_action/cancel_goal"
CANCEL_TIMEOUT_S = 1.0  # an action server that has not answered by then counts as not answering
ZERO_FOR_S = 1.0  # zero velocity on the command topic this long after the answers
ZERO_HZ = 10.0
CANCEL_ALL = {"goal_info": {"goal_id": {"uuid": [0] * 16}, "stamp": {"sec": 0, "nanosec": 0}}}


class Cancel(Enum):
    """What became of one action's cancel request."""

    CANCELLED = "cancelled"  # goals were cancelling
    NO_GOAL = "no goal"  # the server answered: nothing to cancel
    NO_SERVER = "no server"  # no such action server (its cancel service does not exist)
    FAILED = "failed"  # refused, or no answer in CANCEL_TIMEOUT_S
    PENDING = "pending"  # not answered yet when the robot answered a fleet stop (still asked)


@dataclass(frozen=True, slots=True)
class ActionCancel:
    action: str
    outcome: Cancel
    goals: int = 0
    detail: str = ""


def cancel_outcome(action: str, values: object) -> ActionCancel:
    """A ``CancelGoal`` response (rosbridge JSON) as an :class:`ActionCancel`."""
    goals = values.get("goals_canceling") if isinstance(values, Mapping) else None
    code = values.get("return_code") if isinstance(values, Mapping) else None
    if isinstance(goals, list) and goals:
        return ActionCancel(action, Cancel.CANCELLED, len(goals))
    if code in (0, 2, 3, None):  # none, unknown goal id, goal already terminated: nothing runs
        return ActionCancel(action, Cancel.NO_GOAL)
    return ActionCancel(action, Cancel.FAILED, detail=f"refused (return code {code})")


def cancel_failure(action: str, error: str) -> ActionCancel:
    """A ``call_service`` that failed: the service does not exist (no such server) or another error."""
    text = str(error)
    if "does not exist" in text or "not available" in text or "not exposed" in text:
        return ActionCancel(action, Cancel.NO_SERVER, detail=text[:120])
    return ActionCancel(action, Cancel.FAILED, detail=text[:120])
