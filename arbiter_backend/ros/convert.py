"""rosbridge JSON <-> ROS 2 messages, for any installed type, by introspecting the generated classes.

A message class says what it holds: ``get_fields_and_field_types()`` names the
fields and ``SLOT_TYPES`` gives each one's rosidl type (basic, string, nested
message, array, bounded or unbounded sequence). Both directions walk those, so
there is no table per type. The conventions are rosbridge's: missing fields keep
their defaults, unknown fields are errors, ints are accepted for floats (not floats for ints), a
Time takes ROS 1's ``secs``/``nsecs`` or ``"now"``, a Header given without a stamp is stamped now,
``uint8[]``/``char[]``/``byte[]`` travel as base64 strings (lists of ints are
accepted on the way in), non-finite floats leave as ``null`` (JSON has no NaN).
``to_cbor`` gives rosbridge's CBOR form (``cborenc``).
"""

from __future__ import annotations

import base64
import binascii
import importlib
import math
import os
import sys
import time
from functools import lru_cache
from typing import Any

from rosidl_parser import definition as rd

from arbiter_core import msgtypes
from arbiter_core.msgtypes import MessageError, interface_message, normalize_type
from arbiter_core.topics import stamp

from .. import cborenc
from ..jsonframe import Base64Text

_FLOATS = {"float", "double", "long double"}
_BYTES = {"octet", "uint8", "char"}
_INT_RANGES = {
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "char": (0, 2**8 - 1),
    "octet": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
    "wchar": (0, 2**16 - 1),
}
MAX_DEPTH = 32


@lru_cache(maxsize=256)
def message_class(type_name: str) -> type[Any]:
    """The generated class for ``pkg/msg/Type`` (or ``pkg/Type``), or for a message of a service or an
    action (``pkg/srv/Name_Event``, ``pkg/action/Name_FeedbackMessage``: ``msgtypes.normalize_type``);
    MessageError if it is not installed."""
    full = normalize_type(type_name)
    pkg, kind, name = full.split("/")
    try:
        module = importlib.import_module(f"{pkg}.{kind}")
        cls: type[Any] = getattr(module, name, None) or _action_part(module, full)
    except (ImportError, AttributeError, ValueError):
        raise MessageError(f"message type {full} is not installed") from None
    if not hasattr(cls, "get_fields_and_field_types"):
        raise MessageError(f"{full} is not a message type")
    return cls


def _action_part(module: Any, full: str) -> type[Any]:
    """An action's Goal, Result, Feedback or FeedbackMessage: attributes of the action's class, not of
    its package's module (AttributeError when ``full`` is none of them)."""
    parts = interface_message(full)
    if parts is None or parts[1] != "action":
        raise AttributeError(full)
    action = getattr(module, parts[2])
    part: type[Any] = getattr(action.Impl if parts[3] == "FeedbackMessage" else action, parts[3])
    return part


@lru_cache(maxsize=128)
def service_class(type_name: str) -> type[Any]:
    """The generated class for ``pkg/srv/Name`` (or ``pkg/Name``); MessageError if it is not installed."""
    parts = type_name.split("/")
    if len(parts) == 3 and parts[1] == "srv":
        pkg, name = parts[0], parts[2]
    elif len(parts) == 2:
        pkg, name = parts
    else:
        raise MessageError(f"invalid service type name {type_name[:80]!r}")
    try:
        cls: type[Any] = getattr(importlib.import_module(f"{pkg}.srv"), name)
    except (ImportError, AttributeError, ValueError):
        raise MessageError(f"service type {pkg}/srv/{name} is not installed here") from None
    if not hasattr(cls, "Request"):
        raise MessageError(f"{pkg}/srv/{name} is not a service type")
    return cls


def _interface_class(type_name: str, kind: str, marker: str) -> type[Any]:
    """The generated class for ``pkg/<kind>/Name`` (or ``pkg/Name``); MessageError if it is not installed."""
    parts = type_name.split("/") if isinstance(type_name, str) else []
    if len(parts) == 3 and parts[1] == kind:
        pkg, name = parts[0], parts[2]
    elif len(parts) == 2:
        pkg, name = parts
    else:
        raise MessageError(f"invalid {kind} type name {str(type_name)[:80]!r}")
    try:
        cls: type[Any] = getattr(importlib.import_module(f"{pkg}.{kind}"), name)
    except (ImportError, AttributeError, ValueError):
        raise MessageError(f"{kind} type {pkg}/{kind}/{name} is not installed here") from None
    if not hasattr(cls, marker):
        raise MessageError(f"{pkg}/{kind}/{name} is not a{'n' if kind == 'action' else ''} {kind} type")
    return cls


@lru_cache(maxsize=128)
def action_class(type_name: str) -> type[Any]:
    """The generated class for ``pkg/action/Name`` (or ``pkg/Name``); MessageError if not installed."""
    return _interface_class(type_name, "action", "Goal")


def interface_name(cls: type, kind: str) -> str:
    """``std_srvs.srv.SetBool`` -> ``std_srvs/srv/SetBool`` (``kind``: srv or action)."""
    return f"{cls.__module__.split('.')[0]}/{kind}/{cls.__name__}"


def type_name_of(cls: type) -> str:
    """``geometry_msgs.msg.Twist`` -> ``geometry_msgs/msg/Twist``; ``std_srvs.srv.Trigger_Event`` ->
    ``std_srvs/srv/Trigger_Event``."""
    pkg, kind = [*cls.__module__.split("."), "msg"][:2]
    return f"{pkg}/{kind}/{cls.__name__}"


# mypy takes no class for Hashable (python/mypy#11470), which the cache asks of its arguments: the
# callers' `ignore[arg-type]`s
@lru_cache(maxsize=256)
def _fields(cls: type[Any]) -> tuple[tuple[str, Any], ...]:
    return tuple(zip(cls.get_fields_and_field_types(), cls.SLOT_TYPES, strict=True))


def _nested_class(t: rd.NamespacedType) -> type[Any]:
    return message_class("/".join([*t.namespaces, t.name]))


@lru_cache(maxsize=1)
def _header_class() -> type[Any] | None:
    try:
        return message_class("std_msgs/msg/Header")
    except MessageError:
        return None


def _share_dir(pkg: str) -> str:
    """A package's share directory: from the ament index (a sourced ROS 2), else beside this Python's
    prefix (the PyPI wheels install ``share/<pkg>`` there and set no AMENT_PREFIX_PATH)."""
    try:
        from ament_index_python.packages import get_package_share_directory

        return str(get_package_share_directory(pkg))
    except Exception:
        return os.path.join(sys.prefix, "share", pkg)


@lru_cache(maxsize=128)
def typedef_text(type_name: str) -> str:
    """The full definition of a message type, as ``gendeps --cat`` and rosapi's
    ``topics_and_raw_types`` give it: its ``.msg`` text, then each type it uses (depth first, once
    each) after a line of ``=`` and ``MSG: pkg/Type``. A comment line saying why when it cannot be read."""
    out: list[str] = []
    seen: set[str] = set()
    stack = [normalize_type(type_name)]
    root = True
    try:
        while stack:
            full = stack.pop()
            pkg, _, name = full.split("/")
            if not root:
                out.append("\n" + "=" * 80 + f"\nMSG: {pkg}/{name}\n")
            root = False
            with open(os.path.join(_share_dir(pkg), "msg", f"{name}.msg"), encoding="utf-8") as f:
                out.append(f.read())
            for _field, slot in _fields(message_class(full)):  # type: ignore[arg-type]  # mypy#11470, above
                while isinstance(slot, rd.AbstractNestedType):
                    slot = slot.value_type
                if isinstance(slot, rd.NamespacedType):
                    dep = "/".join([*slot.namespaces, slot.name])
                    if dep not in seen:
                        seen.add(dep)
                        stack.append(dep)
    except (OSError, LookupError, MessageError, ValueError) as exc:
        return f"# failed to get full definition text for {type_name}: {exc}"
    return "".join(out)


# -- JSON -> ROS ----------------------------------------------------------------------------------
def _time_of(t: Any) -> str | None:
    """``Time`` or ``Duration`` for a ``builtin_interfaces`` time field, else None."""
    if isinstance(t, rd.NamespacedType) and list(t.namespaces)[:1] == ["builtin_interfaces"]:
        return t.name if t.name in ("Time", "Duration") else None
    return None


@lru_cache(maxsize=256)
def _layout(cls: type[Any]) -> tuple[str | None, dict[str, Any], dict[str, str]]:
    """What ``to_ros`` needs of a class, once: ``Time``/``Duration``/``Header`` for those (else None),
    its fields' rosidl types by name, and which fields are a Time or Duration."""
    special = None
    if cls.__module__.startswith("builtin_interfaces.") and cls.__name__ in ("Time", "Duration"):
        special = cls.__name__
    elif cls is _header_class():
        special = "Header"
    fields = dict(_fields(cls))  # type: ignore[arg-type]  # a class hashes: python/mypy#11470
    times = {name: kind for name, t in fields.items() if (kind := _time_of(t)) is not None}
    return special, fields, times


def _time(kind: str, value: Any, inst: Any, path: str, now_base: bool = False) -> Any:
    """``inst`` (a ``builtin_interfaces`` Time or Duration) set from rosbridge JSON
    (``msgtypes.time_fields``: ROS 1's ``secs``/``nsecs`` too, a Time may be ``"now"``); a field not
    given keeps ``inst``'s value, or now's where ``now_base`` (a Header's stamp, as rosbridge)."""
    given = msgtypes.time_fields(value, path, now_ok=kind == "Time")
    if given is None:
        given = stamp(time.time_ns())
    elif now_base and len(given) < 2:
        given = {**stamp(time.time_ns()), **given}
    for field, typename in (("sec", "int32"), ("nanosec", "uint32")):
        if field in given:
            setattr(inst, field, _basic(typename, given[field], f"{path}.{field}"))
    return inst


def to_ros(cls: type, data: Any, path: str = "msg", depth: int = 0) -> Any:
    """Build an instance of ``cls`` from rosbridge JSON; MessageError naming the field on any mismatch.
    As rosbridge: a ``std_msgs/Header`` given without a stamp is stamped now."""
    if depth > MAX_DEPTH:
        raise MessageError(f"{path}: nested too deeply")
    special, fields, times = _layout(cls)
    if special in ("Time", "Duration"):
        return _time(cls.__name__, data, cls(), path)  # a Time or Duration published as it is
    if not isinstance(data, dict):
        raise MessageError(f"{path} must be an object, got {_kind(data)}")
    msg = cls()
    if special == "Header" and "stamp" not in data:
        _time("Time", "now", msg.stamp, path)
    for key, value in data.items():
        slot = fields.get(key)
        if slot is None:
            raise MessageError(f"{path} has unknown field {str(key)[:40]!r}")
        kind = times.get(key)
        if kind is not None:  # set in place on the default instance
            _time(kind, value, getattr(msg, key), f"{path}.{key}", now_base=special == "Header")
            continue
        converted = _to_ros_value(slot, value, f"{path}.{key}", depth)
        try:
            setattr(msg, key, converted)
        except (AssertionError, TypeError, ValueError, OverflowError) as exc:
            raise MessageError(f"{path}.{key}: {exc}") from None
    return msg


def _to_ros_value(t: Any, value: Any, path: str, depth: int) -> Any:
    if isinstance(t, rd.BasicType):
        return _basic(t.typename, value, path)
    if isinstance(t, (rd.AbstractString, rd.AbstractWString)):
        if not isinstance(value, str):
            raise MessageError(f"{path} must be a string, got {_kind(value)}")
        return value
    if isinstance(t, rd.NamespacedType):
        kind = _time_of(t)
        if kind is not None:
            return _time(kind, value, _nested_class(t)(), path)
        return to_ros(_nested_class(t), value, path, depth + 1)
    if isinstance(t, rd.AbstractNestedType):
        elem = t.value_type
        if isinstance(elem, rd.BasicType) and elem.typename in _BYTES and isinstance(value, str):
            try:
                raw = base64.b64decode(value, validate=True)
            except (binascii.Error, ValueError):
                raise MessageError(f"{path} must be base64 or a list of integers") from None
            value = list(raw)
        if not isinstance(value, list):
            raise MessageError(f"{path} must be an array, got {_kind(value)}")
        if isinstance(t, rd.Array) and len(value) != t.size:
            raise MessageError(f"{path} must have exactly {t.size} elements, got {len(value)}")
        if isinstance(t, rd.BoundedSequence) and len(value) > t.maximum_size:
            raise MessageError(f"{path} may have at most {t.maximum_size} elements, got {len(value)}")
        return [_to_ros_value(elem, v, f"{path}[{i}]", depth + 1) for i, v in enumerate(value)]
    raise MessageError(f"{path}: unsupported field type {type(t).__name__}")


def _basic(typename: str, value: Any, path: str) -> Any:
    if typename == "boolean":
        if not isinstance(value, bool):
            raise MessageError(f"{path} must be true or false, got {_kind(value)}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise MessageError(f"{path} must be a number, got {_kind(value)}")
    if typename in _FLOATS:
        try:
            f = float(value)
        except OverflowError:
            raise MessageError(f"{path} is too large for {typename}") from None
        if not math.isfinite(f):
            raise MessageError(f"{path} must be finite")
        return f
    if isinstance(value, float):  # as rosbridge and the embedded transport: 2.0 is not an integer
        raise MessageError(f"{path} must be an integer, got {value!r}")
    lo, hi = _INT_RANGES.get(typename, (-(2**63), 2**64 - 1))
    if not lo <= value <= hi:
        raise MessageError(f"{path} is out of range for {typename}")
    # rclpy holds an octet as one byte; given an int its setter keeps something else (7 reached a
    # subscriber as 223), with no error
    return bytes([value]) if typename == "octet" else value


# -- ROS -> JSON ----------------------------------------------------------------------------------
def to_json(msg: Any) -> dict[str, Any]:
    """rosbridge JSON of a message instance."""
    return {
        name: _to_json_value(t, getattr(msg, name))
        for name, t in _fields(type(msg))  # type: ignore[arg-type]  # a class hashes: python/mypy#11470
    }


def _to_json_value(t: Any, value: Any) -> Any:
    if isinstance(t, rd.BasicType):
        return _basic_json(t.typename, value)
    if isinstance(t, (rd.AbstractString, rd.AbstractWString)):
        return value
    if isinstance(t, rd.NamespacedType):
        return to_json(value)
    if isinstance(t, rd.AbstractNestedType):
        elem = t.value_type
        if isinstance(elem, rd.BasicType):
            if elem.typename in _BYTES:
                raw = b"".join(value) if elem.typename == "octet" else _octets(value)
                # straight into the marked string (spliced into frames, not escaped): one copy of a
                # camera's 3.7 MB of base64 instead of three
                return Base64Text(binascii.b2a_base64(raw, newline=False), "ascii")
            return [_basic_json(elem.typename, v) for v in value]
        return [_to_json_value(elem, v) for v in value]
    return None


def _octets(value: Any) -> Any:
    """The bytes of a ``uint8[]``/``char[]`` field, without a copy where it is a buffer of single bytes
    (rclpy gives ``array('B')``, or a numpy array for a fixed size); a list of ints is copied."""
    try:
        view = memoryview(value)
    except TypeError:
        return bytes(bytearray(value))
    if view.itemsize != 1 or not view.c_contiguous:
        return bytes(bytearray(value))
    return view.cast("B")


def _basic_json(typename: str, value: Any) -> Any:
    if typename == "boolean":
        return bool(value)
    if typename in _FLOATS:
        f = float(value)
        return f if math.isfinite(f) else None
    if typename == "octet" and isinstance(value, bytes):
        return value[0] if value else 0
    return int(value)


# -- ROS -> CBOR (rosbridge's "cbor" compression) -------------------------------------------------
_TYPED = {"float": "float32", "double": "float64", **{t: t for t in cborenc.TYPED_ARRAY_TAGS}}


def to_cbor(msg: Any) -> dict[str, Any]:
    """The CBOR form of a message instance (``cborenc``): byte arrays as bytes, numeric arrays as
    little-endian typed arrays, fixed-size ones included (rosbridge fails on those)."""
    return {
        name: _to_cbor_value(t, getattr(msg, name))
        for name, t in _fields(type(msg))  # type: ignore[arg-type]  # a class hashes: python/mypy#11470
    }


def _to_cbor_value(t: Any, value: Any) -> Any:
    if isinstance(t, rd.NamespacedType):
        return to_cbor(value)
    if isinstance(t, rd.AbstractNestedType):
        elem = t.value_type
        if isinstance(elem, rd.BasicType):
            if elem.typename in _BYTES:
                return b"".join(value) if elem.typename == "octet" else bytes(bytearray(value))
            typed = _TYPED.get(elem.typename)
            if typed is not None:
                return cborenc.typed_array(typed, value)
            return [_basic_cbor(elem.typename, v) for v in value]
        return [_to_cbor_value(elem, v) for v in value]
    if isinstance(t, rd.BasicType):
        return _basic_cbor(t.typename, value)
    return value  # strings


def _basic_cbor(typename: str, value: Any) -> Any:
    if typename in _FLOATS:
        return float(value)  # CBOR holds NaN and infinities as they are
    return _basic_json(typename, value)


def _kind(value: Any) -> str:
    return "null" if value is None else type(value).__name__
