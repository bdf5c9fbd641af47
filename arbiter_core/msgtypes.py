"""ROS message types in rosbridge's JSON form, for the embedded transport (no ROS install).

Knows the handful of types the product carries and checks a message against
them the way rosbridge does: unknown fields and wrong kinds are errors, ints
are accepted for floats, ``null`` is never accepted, missing fields get their
defaults. Types it does not know pass through as any JSON object.
"""

from __future__ import annotations

import math
import re
from typing import Any

Spec = dict[str, Any]

_TIME: Spec = {"sec": "int32", "nanosec": "uint32"}
_VECTOR3: Spec = {"x": "float64", "y": "float64", "z": "float64"}
_HEADER: Spec = {"stamp": _TIME, "frame_id": "string"}
_QUAT: Spec = {"x": "float64", "y": "float64", "z": "float64", "w": "float64"}
_TWIST: Spec = {"linear": _VECTOR3, "angular": _VECTOR3}
_POSE: Spec = {"position": _VECTOR3, "orientation": _QUAT}

TYPES: dict[str, Spec] = {
    "std_msgs/msg/String": {"data": "string"},
    "std_msgs/msg/Header": _HEADER,
    "builtin_interfaces/msg/Time": _TIME,
    "geometry_msgs/msg/Vector3": _VECTOR3,
    "geometry_msgs/msg/Twist": _TWIST,
    "geometry_msgs/msg/TwistStamped": {"header": _HEADER, "twist": _TWIST},
    "geometry_msgs/msg/Quaternion": _QUAT,
    "geometry_msgs/msg/Pose": _POSE,
    "nav_msgs/msg/Odometry": {
        "header": _HEADER,
        "child_frame_id": "string",
        "pose": {"pose": _POSE, "covariance": ("float64", 36)},
        "twist": {"twist": _TWIST, "covariance": ("float64", 36)},
    },
}

_TYPE_RE = re.compile(r"^([A-Za-z][A-Za-z0-9_]*)/(?:(msg)/)?([A-Za-z][A-Za-z0-9_]*)$")
# the messages rosidl generates for a service or an action, which travel on topics of their own: a
# service's ``_service_event`` topic (``pkg/srv/Name_Event``, with introspection on) and an action's
# ``_action/feedback`` (``pkg/action/Name_FeedbackMessage``); the rest for completeness
SRV_MESSAGES = ("Request", "Response", "Event")
ACTION_MESSAGES = (
    "Goal", "Result", "Feedback", "FeedbackMessage",
    *(f"{call}_{part}" for call in ("SendGoal", "GetResult") for part in SRV_MESSAGES),
)  # fmt: skip
_INTERFACE_MESSAGE_RE = re.compile(
    r"^([A-Za-z][A-Za-z0-9_]*)/(srv|action)/([A-Za-z][A-Za-z0-9]*)_([A-Za-z_]+)$"
)
_INT_RANGES = {"int32": (-(2**31), 2**31 - 1), "uint32": (0, 2**32 - 1)}
_QUAT_DEFAULT_W = 1.0


class MessageError(ValueError):
    """A message that does not fit its type."""


def normalize_type(name: Any) -> str:
    """``pkg/Type`` and ``pkg/msg/Type`` -> ``pkg/msg/Type``; a message generated for a service or an
    action (``pkg/srv/Name_Event``, ``pkg/action/Name_FeedbackMessage``, see ``SRV_MESSAGES`` and
    ``ACTION_MESSAGES``) as it is; raises MessageError for anything else."""
    if not isinstance(name, str):
        raise MessageError(f"type must be a string, got {type(name).__name__}")
    m = _TYPE_RE.match(name)
    if m:
        return f"{m.group(1)}/msg/{m.group(3)}"
    if interface_message(name) is None:
        raise MessageError(f"invalid message type name {name[:80]!r}")
    return name


def interface_message(name: str) -> tuple[str, str, str, str] | None:
    """``pkg/srv/Name_Event`` -> ``(pkg, "srv", Name, "Event")`` (likewise ``action``); None when
    ``name`` is not a message rosidl generates for a service or an action."""
    m = _INTERFACE_MESSAGE_RE.match(name)
    if not m:
        return None
    pkg, kind, base, part = m.groups()
    if part not in (SRV_MESSAGES if kind == "srv" else ACTION_MESSAGES):
        return None
    return pkg, kind, base, part


def _default(spec: Any) -> Any:
    if isinstance(spec, dict):
        out = {k: _default(v) for k, v in spec.items()}
        if spec is _QUAT:
            out["w"] = _QUAT_DEFAULT_W
        return out
    if isinstance(spec, tuple):
        return [_default(spec[0])] * spec[1]
    if spec == "string":
        return ""
    if spec in _INT_RANGES:
        return 0
    return 0.0


def _check(spec: Any, value: Any, path: str) -> Any:
    if isinstance(spec, dict):
        if not isinstance(value, dict):
            raise MessageError(f"{path or 'msg'} must be an object, got {_kind(value)}")
        unknown = set(value) - set(spec)
        if unknown:
            raise MessageError(f"{path or 'msg'} has unknown field {sorted(unknown)[0]!r}")
        out = {}
        for key, sub in spec.items():
            sub_path = f"{path}.{key}" if path else key
            out[key] = _check(sub, value[key], sub_path) if key in value else _default(sub)
        if spec is _QUAT and "w" not in value:
            out["w"] = _QUAT_DEFAULT_W
        return out
    if isinstance(spec, tuple):
        elem, size = spec
        if not isinstance(value, list) or len(value) != size:
            raise MessageError(f"{path} must be an array of {size} {elem}")
        return [_check(elem, v, f"{path}[{i}]") for i, v in enumerate(value)]
    if spec == "string":
        if not isinstance(value, str):
            raise MessageError(f"{path} must be a string, got {_kind(value)}")
        return value
    if spec in _INT_RANGES:
        if isinstance(value, bool) or not isinstance(value, int):
            raise MessageError(f"{path} must be an integer, got {_kind(value)}")
        lo, hi = _INT_RANGES[spec]
        if not lo <= value <= hi:
            raise MessageError(f"{path} is out of range for {spec}")
        return value
    # float64
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise MessageError(f"{path} must be a number, got {_kind(value)}")
    try:
        return float(value)
    except OverflowError:
        return math.copysign(math.inf, value)


def _kind(value: Any) -> str:
    return "null" if value is None else type(value).__name__


def check_message(type_name: str, msg: Any) -> dict[str, Any]:
    """Validate ``msg`` against ``type_name`` (normalised) and return it with defaults filled."""
    spec = TYPES.get(type_name)
    if spec is None:
        if not isinstance(msg, dict):
            raise MessageError(f"msg must be an object, got {_kind(msg)}")
        return msg
    checked: dict[str, Any] = _check(spec, msg, "")
    return checked


def known(type_name: str) -> bool:
    return type_name in TYPES
