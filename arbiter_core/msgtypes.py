"""ROS message types in rosbridge's JSON form, for the embedded transport (no ROS install).

Knows the handful of types the product carries and checks a message against
them the way rosbridge does: unknown fields and wrong kinds are errors, ints
are accepted for floats, ``null`` is never accepted, missing fields get their
defaults, a Time takes ROS 1's ``secs``/``nsecs`` too or ``"now"``, a Header
given without a stamp is stamped now. Types it does not know pass through as
any JSON object.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable
from typing import Any

from .topics import stamp

Spec = dict[str, Any]
Clock = Callable[[], int]  # now, in ns since the epoch

_TIME: Spec = {"sec": "int32", "nanosec": "uint32"}
_VECTOR3: Spec = {"x": "float64", "y": "float64", "z": "float64"}
_HEADER: Spec = {"stamp": _TIME, "frame_id": "string"}
_QUAT: Spec = {"x": "float64", "y": "float64", "z": "float64", "w": "float64"}
_TWIST: Spec = {"linear": _VECTOR3, "angular": _VECTOR3}
_POINT: Spec = {"x": "float64", "y": "float64", "z": "float64"}
_POSE: Spec = {"position": _POINT, "orientation": _QUAT}
_POSE_COV: Spec = {"pose": _POSE, "covariance": ("float64", 36)}
_TWIST_COV: Spec = {"twist": _TWIST, "covariance": ("float64", 36)}

TYPES: dict[str, Spec] = {
    "std_msgs/msg/String": {"data": "string"},
    "std_msgs/msg/Header": _HEADER,
    "builtin_interfaces/msg/Time": _TIME,
    "geometry_msgs/msg/Vector3": _VECTOR3,
    "geometry_msgs/msg/Twist": _TWIST,
    "geometry_msgs/msg/TwistStamped": {"header": _HEADER, "twist": _TWIST},
    "geometry_msgs/msg/Quaternion": _QUAT,
    "geometry_msgs/msg/Point": _POINT,
    "geometry_msgs/msg/Pose": _POSE,
    "geometry_msgs/msg/PoseWithCovariance": _POSE_COV,
    "geometry_msgs/msg/TwistWithCovariance": _TWIST_COV,
    "nav_msgs/msg/Odometry": {
        "header": _HEADER,
        "child_frame_id": "string",
        "pose": _POSE_COV,
        "twist": _TWIST_COV,
    },
}
_NAMES = {id(spec): name for name, spec in TYPES.items()}  # a nested spec's type
_ROSIDL = {"float64": "double"}  # the basic types as rosidl (and rosapi's TypeDef) spell them

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


# rosbridge takes a builtin_interfaces Time or Duration by ROS 1's names too (roslibpy's Time sends them)
TIME_ALIASES = {"sec": ("sec", "secs"), "nanosec": ("nanosec", "nsecs")}
TIME_KEYS = frozenset(a for aliases in TIME_ALIASES.values() for a in aliases)


def time_fields(value: Any, path: str, now_ok: bool) -> dict[str, Any] | None:
    """The fields given of a ``builtin_interfaces`` Time or Duration in rosbridge JSON, by their ROS 2
    names (``secs``/``nsecs`` taken for ``sec``/``nanosec``; where both are given ``sec`` wins, as
    rosbridge's ``message_conversion``); None for ``"now"`` (a Time, ``now_ok``). Their values are the
    caller's to check."""
    if now_ok and value == "now":
        return None
    if not isinstance(value, dict):
        either = ' or "now"' if now_ok else ""
        raise MessageError(f"{path} must be an object (sec, nanosec){either}, got {_kind(value)}")
    unknown = set(value) - TIME_KEYS
    if unknown:
        raise MessageError(f"{path} has unknown field {str(sorted(unknown, key=str)[0])[:40]!r}")
    return {
        field: value[next(a for a in aliases if a in value)]
        for field, aliases in TIME_ALIASES.items()
        if any(a in value for a in aliases)
    }


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


def _time(value: Any, path: str, base: dict[str, int], clock: Clock) -> dict[str, int]:
    """A Time as rosbridge takes it (``time_fields``); a field not given keeps ``base``'s value."""
    given = time_fields(value, path, now_ok=True)
    if given is None:
        return stamp(clock())
    return {**base, **{k: _check(_TIME[k], v, f"{path}.{k}", clock) for k, v in given.items()}}


def _check(spec: Any, value: Any, path: str, clock: Clock) -> Any:
    if spec is _TIME:
        return _time(value, path or "msg", _default(_TIME), clock)
    if isinstance(spec, dict):
        if not isinstance(value, dict):
            raise MessageError(f"{path or 'msg'} must be an object, got {_kind(value)}")
        unknown = set(value) - set(spec)
        if unknown:
            raise MessageError(f"{path or 'msg'} has unknown field {sorted(unknown)[0]!r}")
        out: dict[str, Any] = {}
        for key, sub in spec.items():
            sub_path = f"{path}.{key}" if path else key
            if spec is _HEADER and key == "stamp":  # as rosbridge: a header given is stamped now
                now = stamp(clock())
                out[key] = _time(value[key], sub_path, now, clock) if key in value else now
                continue
            out[key] = _check(sub, value[key], sub_path, clock) if key in value else _default(sub)
        if spec is _QUAT and "w" not in value:
            out["w"] = _QUAT_DEFAULT_W
        return out
    if isinstance(spec, tuple):
        elem, size = spec
        if not isinstance(value, list) or len(value) != size:
            raise MessageError(f"{path} must be an array of {size} {elem}")
        return [_check(elem, v, f"{path}[{i}]", clock) for i, v in enumerate(value)]
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


def check_message(type_name: str, msg: Any, clock: Clock = time.time_ns) -> dict[str, Any]:
    """Validate ``msg`` against ``type_name`` (normalised) and return it with defaults filled, as
    rosbridge's ``message_conversion`` takes it: ``secs``/``nsecs`` for a Time's ``sec``/``nanosec``, a
    Time ``"now"``, a Header given without a stamp stamped now (``clock``: ns since the epoch)."""
    spec = TYPES.get(type_name)
    if spec is None:
        if not isinstance(msg, dict):
            raise MessageError(f"msg must be an object, got {_kind(msg)}")
        return msg
    checked: dict[str, Any] = _check(spec, msg, "", clock)
    return checked


def known(type_name: str) -> bool:
    return type_name in TYPES


def typedefs(type_name: str) -> list[dict[str, Any]]:
    """rosapi's ``message_details`` for a type this module knows (the embedded transport's): its
    ``TypeDef`` and those of the types it holds, depth first, each once, as the ROS transport gives them
    from the installed classes (``arbiter_backend/ros/typedefs.py``); [] for any other type."""
    try:
        spec = TYPES.get(normalize_type(type_name))
    except MessageError:
        return []
    out: list[dict[str, Any]] = []
    if spec is not None:
        _typedefs(spec, out, set())
    return out


def _typedefs(spec: Spec, out: list[dict[str, Any]], seen: set[str]) -> None:
    pkg, _, name = _NAMES[id(spec)].split("/")
    seen.add(f"{pkg}/{name}")
    default = _default(spec)
    fields: list[tuple[str, str, int, str]] = []  # name, type, array length, example
    for key, sub in spec.items():
        elem, size = sub if isinstance(sub, tuple) else (sub, -1)
        if isinstance(elem, dict):
            ty, _, short = _NAMES[id(elem)].split("/")
            fields.append((key, f"{ty}/{short}", size, "{}" if size < 0 else "[]"))
        else:
            fields.append((key, _ROSIDL.get(elem, str(elem)), size, str(default[key]) if size < 0 else "[]"))
    out.append(
        {
            "type": f"{pkg}/{name}",
            "fieldnames": [f[0] for f in fields],
            "fieldtypes": [f[1] for f in fields],
            "fieldarraylen": [f[2] for f in fields],
            "examples": [f[3] for f in fields],
            "constnames": [],
            "constvalues": [],
        }
    )
    for sub in spec.values():
        elem = sub[0] if isinstance(sub, tuple) else sub
        if isinstance(elem, dict) and _NAMES[id(elem)].replace("/msg/", "/") not in seen:
            _typedefs(elem, out, seen)
