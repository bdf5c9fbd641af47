"""The ROS graph contract (names, types, QoS depth) and the messages both transports publish.

Pure: messages are built in rosbridge JSON form; the ROS transport converts them
with ``ros.convert``, so each message is defined once for both transports.
"""

from __future__ import annotations

import functools
import re
from typing import Any

# Names without the leading slash resolve to /stamped_cmd_vel etc. in the root namespace and
# follow a namespace remap (``--ros-args -r __ns:=/robot1``) in ROS mode.
STAMPED = "stamped_cmd_vel"
MEASURED = "cmd_vel_measured"
REPORT = "latency_report"
ODOM = "odom"
BRIDGE_NODE = "arbiter_bridge"  # the backend's rosbridge node: a client's ``~`` names resolve under it

TYPE_STRING = "std_msgs/msg/String"
TYPE_TWIST = "geometry_msgs/msg/Twist"
TYPE_TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
TYPE_ODOM = "nav_msgs/msg/Odometry"

MEASURED_TYPES = {"twist": TYPE_TWIST, "twist_stamped": TYPE_TWIST_STAMPED}
QOS_DEPTH = 10  # reliable, volatile, keep last 10: a late subscriber never gets old commands

# Velocity commands: whoever relays them (our bridge in ROS mode) keeps them volatile, so that a subscriber
# that joins late never receives a command from before it joined; other relayed topics may be kept briefly.
COMMAND_NAMES = frozenset({STAMPED, MEASURED, "cmd_vel"})
COMMAND_TYPES = frozenset({TYPE_TWIST, TYPE_TWIST_STAMPED})


def is_command(topic: str, type_name: str) -> bool:
    """A velocity command, by its topic's last name (any namespace) or its type."""
    return topic.rstrip("/").rsplit("/", 1)[-1] in COMMAND_NAMES or type_name in COMMAND_TYPES


def is_hidden(name: str) -> bool:
    """A hidden topic or service (rclpy's ``topic_or_service_is_hidden``): a part starts with ``_``,
    as an action's ``/fibonacci/_action/status`` does; ``ros2 topic list`` and rosapi leave them out."""
    return any(part.startswith("_") for part in name.split("/"))


def stamp(ns: int) -> dict[str, int]:
    """A ``builtin_interfaces/Time`` in rosbridge JSON form, from integer nanoseconds."""
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def twist(v: float, w: float) -> dict[str, Any]:
    return {"linear": {"x": v, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": w}}


def measured_message(v: float, w: float, measured_type: str, stamp_ns: int) -> dict[str, Any]:
    """``/cmd_vel_measured``: a Twist, or a TwistStamped stamped with the tracker's receive time."""
    if MEASURED_TYPES[measured_type] == TYPE_TWIST:
        return twist(v, w)
    return {
        "header": {
            "stamp": stamp(stamp_ns),
            "frame_id": "base_link",
        },
        "twist": twist(v, w),
    }


# -- names, the ROS way ---------------------------------------------------------------------------
class TopicNameError(ValueError):
    """A namespace or topic name that ROS 2 would refuse."""


_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _check_tokens(name: str, what: str) -> None:
    parts = [p for p in name.strip("/").split("/")] if name.strip("/") else []
    for part in parts:
        if not _TOKEN.fullmatch(part):
            raise TopicNameError(
                f"{what} {name!r}: each part must start with a letter or _ and hold only letters, "
                "digits and _ (no //, no trailing /)"
            )
    if "//" in name or (name.endswith("/") and name != "/"):
        raise TopicNameError(f"{what} {name!r}: no empty parts and no trailing /")


def namespace(text: str | None) -> str:
    """A namespace as ROS writes it: ``""`` for the root, else ``/a/b`` (a leading / is added)."""
    if text is None or text in ("", "/"):
        return ""
    ns = text if text.startswith("/") else "/" + text
    _check_tokens(ns, "namespace")
    return ns


_SUBSTITUTION = re.compile(r"\{([^{}]*)\}")


@functools.lru_cache(maxsize=4096)  # on every frame a client sends: a name resolves once
def resolve(name: str, ns: str = "", what: str = "topic", node: str | None = None) -> str:
    """A topic, service, action or node name resolved the ROS way, as rcl's ``rcl_expand_topic_name``
    does it for a node ``node`` in namespace ``ns`` (what rosbridge_suite's node does with every name a
    client gives it): absolute names as given; relative ones under ``ns`` (``odom`` in ``/robot1``:
    ``/robot1/odom``; in the root: ``/odom``); ``~`` is the node's own name (``~/x``: ``/ns/node/x``);
    ``{node}``, ``{ns}`` and ``{namespace}`` are substituted. Without ``node`` (a command-line flag, not a
    node's name) a ``~`` or ``{node}`` name is refused. TopicNameError says why a name is not one."""
    if not name:
        raise TopicNameError(f"a {what} name cannot be empty")
    if "~" in name[1:]:
        raise TopicNameError(f"{what} {name!r}: '~' may only be the first character")
    if name.startswith("~") and len(name) > 2 and name[1] != "/":  # rcl's rule: "~x" passes, "~xy" not
        raise TopicNameError(f"{what} {name!r}: '~' must be followed by '/'")
    if name.startswith("~") and node is None:
        raise TopicNameError(f"{what} {name!r}: a private (~) name belongs to a node; give the full name")
    root = ns.rstrip("/")
    values = {"ns": root or "/", "namespace": root or "/"}
    if node is not None:
        values["node"] = node

    def substitute(m: re.Match[str]) -> str:
        key = m.group(1)
        if key not in values:
            raise TopicNameError(f"{what} {name!r}: unknown substitution {{{key}}}")
        return values[key]

    expanded = _SUBSTITUTION.sub(substitute, name)
    if expanded.startswith("~"):
        expanded = f"{root}/{node}{expanded[1:]}"
    elif not expanded.startswith("/"):
        expanded = f"{root}/{expanded}"
    _check_tokens(expanded, what)
    if not expanded.strip("/"):
        raise TopicNameError(f"a {what} name cannot be empty")
    return expanded
