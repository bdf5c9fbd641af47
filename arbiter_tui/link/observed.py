"""rosbridge messages (JSON) of a robot's own topics into an :class:`Observer`'s calls: the odometry,
the command (Twist or TwistStamped), the plan, the goal and an action's goal status. Stamped with this
host's clock on arrival, so a TwistStamped's age is this host's receive time minus the sender's stamp
(docs/analytics.md, "Grade any controller"). A message that does not parse is skipped: a foreign robot's
topics are not ours to trust."""

from __future__ import annotations

import time
from typing import Any

from arbiter_core.kinematics import pose_of_odometry

from ..analytics.observe import Observer

TYPE_TWIST = "geometry_msgs/Twist"
TYPE_TWIST_STAMPED = "geometry_msgs/TwistStamped"
TYPE_PATH = "nav_msgs/Path"
TYPE_POSE_STAMPED = "geometry_msgs/PoseStamped"
TYPE_GOAL_STATUS_ARRAY = "action_msgs/GoalStatusArray"  # on <action>/_action/status
_BAD = (KeyError, TypeError, ValueError, IndexError)


def _stamp_ns(header: Any) -> int | None:
    stamp = header["stamp"]
    ns = int(stamp["sec"]) * 1_000_000_000 + int(stamp.get("nanosec", stamp.get("nsec", 0)))
    return ns if ns > 0 else None


def observe_odometry(observer: Observer, msg: dict[str, Any]) -> None:
    now = time.time_ns()
    if not observer.wants_odometry(now):
        return
    try:
        pose = pose_of_odometry(msg)
        tw = msg["twist"]["twist"]
        values = (pose.x, pose.y, pose.theta, float(tw["linear"]["x"]), float(tw["angular"]["z"]))
    except _BAD:
        return
    observer.on_odometry(now, *values)


def observe_command(observer: Observer, msg: dict[str, Any], stamped: bool) -> None:
    now = time.time_ns()
    try:
        twist = msg["twist"] if stamped else msg
        v, w = float(twist["linear"]["x"]), float(twist["angular"]["z"])
        stamp = _stamp_ns(msg["header"]) if stamped else None
    except _BAD:
        return
    observer.on_command(now, v, w, stamp)


def observe_plan(observer: Observer, msg: dict[str, Any]) -> None:
    now = time.time_ns()
    try:
        points = [
            (float(p["pose"]["position"]["x"]), float(p["pose"]["position"]["y"])) for p in msg["poses"]
        ]
    except _BAD:
        return
    observer.on_plan(now, points)


def observe_goal(observer: Observer, msg: dict[str, Any]) -> None:
    now = time.time_ns()
    try:
        x, y = float(msg["pose"]["position"]["x"]), float(msg["pose"]["position"]["y"])
    except _BAD:
        return
    observer.on_goal(now, x, y)


def goal_statuses(msg: dict[str, Any]) -> list[tuple[str, int]]:
    """(goal id, status) of each goal in a rosbridge ``action_msgs/GoalStatusArray``. The id is opaque:
    rosbridge sends the uuid's 16 bytes as a list of numbers, or as base64 text (uint8 arrays). Entries
    that do not parse are left out."""
    out = []
    for entry in msg.get("status_list") or ():
        try:
            uuid = entry["goal_info"]["goal_id"]["uuid"]
            goal_id = uuid if isinstance(uuid, str) else bytes(int(b) & 0xFF for b in uuid).hex()
            out.append((goal_id, int(entry["status"])))
        except (*_BAD, AttributeError):
            continue
    return out


def observe_goal_status(observer: Observer, msg: dict[str, Any]) -> None:
    """An action's status topic (``<action>/_action/status``, e.g. ``/navigate_to_pose/_action/status``):
    the observed run ends with its action goal (``Observer.on_goal_status``)."""
    now = time.time_ns()
    if not isinstance(msg, dict):
        return
    observer.on_goal_status(now, goal_statuses(msg))
