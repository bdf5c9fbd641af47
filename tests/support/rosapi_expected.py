"""What rosbridge_suite's rosapi node answers, derived here from rclpy's own view (the message classes,
the graph), to compare a rosbridge server's answers with. rosapi's rules, as its ``objectutils`` and
``proxy`` apply them: a type is named ``pkg/Name`` (a service's parts ``pkg/Name_Request``), a field's
type is the IDL's (``double``, ``boolean``, ``string``, or ``pkg/Name``), its ``fieldarraylen`` -1
(no array), 0 (a sequence) or N (``T[N]``); the typedefs are the type's and then, depth first, each
field type's not yet listed; atomic types have none.

Compared: ``type``, ``fieldnames``, ``fieldtypes``, ``fieldarraylen``. Not compared: ``examples`` and
``constnames``/``constvalues``, where rosapi 2.1.0 shows Python's ``repr`` of a default and, on the
ROS 2 message classes, lists ``SLOT_TYPES`` and each field's accessor as constants.
"""

from __future__ import annotations

import importlib
import re
from typing import Any

ATOMICS = {
    "bool", "boolean", "byte", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
    "float", "float32", "float64", "double", "string", "octet",
}  # fmt: skip
COMPARED = ("type", "fieldnames", "fieldtypes", "fieldarraylen")
_SEQUENCE = re.compile(r"^sequence<([^<>,]+)>$")
_ARRAY = re.compile(r"^(.+)\[(\d*)\]$")


def _message_class(type_name: str) -> Any:
    """``pkg/Name`` or ``pkg/msg/Name``."""
    parts = type_name.split("/")
    pkg, name = parts[0], parts[-1]
    return getattr(importlib.import_module(f"{pkg}.msg"), name)


def _service_class(type_name: str) -> Any:
    parts = type_name.split("/")
    return getattr(importlib.import_module(f"{parts[0]}.srv"), parts[-1])


def _field(idl_type: str) -> tuple[str, int]:
    if m := _SEQUENCE.match(idl_type):
        return m.group(1), 0
    if m := _ARRAY.match(idl_type):
        return m.group(1), int(m.group(2) or 0)
    return idl_type, -1


def typedef(cls: Any) -> dict[str, Any]:
    """One class's typedef (the compared fields)."""
    fields = cls.get_fields_and_field_types()
    types = [_field(t) for t in fields.values()]
    return {
        "type": f"{cls.__module__.split('.')[0]}/{cls.__name__}",
        "fieldnames": list(fields),
        "fieldtypes": [t for t, _ in types],
        "fieldarraylen": [n for _, n in types],
    }


def _recursive(cls: Any, seen: set[str]) -> list[dict[str, Any]]:
    found = [typedef(cls)]
    for field_type in found[0]["fieldtypes"]:
        if field_type in ATOMICS or field_type in seen:
            continue
        seen.add(field_type)
        found += _recursive(_message_class(field_type), seen)
    return found


def message_details(type_name: str) -> list[dict[str, Any]]:
    """``/rosapi/message_details`` → ``typedefs``."""
    return _recursive(_message_class(type_name), {type_name})


def service_details(type_name: str, part: str) -> list[dict[str, Any]]:
    """``/rosapi/service_request_details`` (part ``Request``) or ``service_response_details``."""
    return _recursive(getattr(_service_class(type_name), part), set())


def compared(typedefs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """An answer's typedefs cut to the compared fields."""
    return [{k: d.get(k) for k in COMPARED} for d in typedefs]


def decoded(type_name: str) -> dict[str, Any]:
    """What roslibjs's ``Ros.decodeTypeDefs`` makes of the typedefs: ``rosmsg show`` as a dict."""

    def walk(cls: Any) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for name, idl_type in cls.get_fields_and_field_types().items():
            base, arraylen = _field(idl_type)
            value = base if base in ATOMICS else walk(_message_class(base))
            out[name] = value if arraylen == -1 else [value]
        return out

    return walk(_message_class(type_name))


def action_servers(topics: list[str]) -> list[str]:
    """``/rosapi/action_servers``: each name with both ``<name>/_action/feedback`` and ``.../status``
    among the graph's topics (hidden ones included), sorted."""
    names = set(topics)
    return sorted(
        t[: -len("/_action/status")]
        for t in names
        if t.endswith("/_action/status") and t[: -len("status")] + "feedback" in names
    )
