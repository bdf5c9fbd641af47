"""Installed message types in rosapi's ``TypeDef`` form (``rosapi_msgs/msg/TypeDef``), for the rosapi
services ``message_details``, ``service_request_details`` and ``service_response_details``, answered as
rosbridge_suite's rosapi node answers them (its ``objectutils``):

- a TypeDef: ``type`` (``pkg/Name``, no ``msg/``; a service's parts ``pkg/Name_Request``,
  ``pkg/Name_Response``), then per field its ``fieldnames``, ``fieldtypes`` (a basic type as rosidl
  spells it: ``double``, ``boolean``, ``octet``…; a message ``pkg/Name``; an array or sequence its
  element type), ``fieldarraylen`` (-1 a single value, 0 a sequence, N an array of N) and
  ``examples`` (the default value as Python prints it, ``[]`` for an array, ``{}`` for a message),
  and the type's constants by name (``constnames``, ``constvalues``, as text, sorted by name);
- the list: the type's TypeDef, then each field's type's, depth first, each type once; a basic type
  has none. ``message_details`` of a type that is not installed is an empty list (as stock); a
  service type that is not installed is an error.

Where the stock node's answer is an artefact of reading rclpy's classes with ``inspect`` it is not
copied: it lists ``SLOT_TYPES`` and each field among the constants, and gives a bounded string or
sequence a type of ``builtin/str`` or ``arra/array``; here a bounded type is its element type
(``string``, ``int32``) and the constants are the message's own.
"""

from __future__ import annotations

import re
from typing import Any

from arbiter_core.msgtypes import MessageError

from .convert import message_class, service_class

# rosapi's atomics: a field of one of these has no TypeDef, and its example is its default value
ATOMICS = frozenset(
    [
        "bool",
        "boolean",
        "byte",
        "int8",
        "uint8",
        "int16",
        "uint16",
        "int32",
        "uint32",
        "int64",
        "uint64",
        "float",
        "float32",
        "float64",
        "double",
        "string",
        "octet",
        "char",
        "wstring",
    ]
)
_SEQUENCE = re.compile(r"^sequence<([^,<>]+)(?:, *\d+)?>$")
_ARRAY = re.compile(r"^(.+)\[(\d*)\]$")
_BOUNDED_STRING = re.compile(r"^(w?string)<\d+>$")
TypeDef = dict[str, Any]


def _field_type(rosidl: str) -> tuple[str, int]:
    """(element type, array length) of a field as ``get_fields_and_field_types`` spells it."""
    arraylen = -1
    m = _SEQUENCE.match(rosidl)
    if m:
        rosidl, arraylen = m.group(1), 0
    else:
        m = _ARRAY.match(rosidl)
        if m:
            rosidl, arraylen = m.group(1), int(m.group(2) or 0)
    bounded = _BOUNDED_STRING.match(rosidl)
    return (bounded.group(1) if bounded else rosidl), arraylen


def _constants(cls: type) -> tuple[list[str], list[str]]:
    meta = type(cls)
    found: dict[str, Any] = getattr(meta, f"_{meta.__name__}__constants", None) or {}
    names = sorted(found)
    return names, [str(found[n]) for n in names]


def typedef(cls: type) -> TypeDef:
    """The TypeDef of one generated message class (a message, or a service's Request or Response)."""
    instance = cls()
    names, types, lengths, examples = [], [], [], []
    for name, rosidl in cls.get_fields_and_field_types().items():  # type: ignore[attr-defined]  # generated
        element, arraylen = _field_type(rosidl)
        names.append(name)
        types.append(element)
        lengths.append(arraylen)
        if arraylen >= 0:
            examples.append("[]")
        elif element not in ATOMICS:
            examples.append("{}")
        else:
            examples.append(str(getattr(instance, name)))
    constnames, constvalues = _constants(cls)
    return {
        "type": f"{cls.__module__.split('.')[0]}/{cls.__name__}",
        "fieldnames": names,
        "fieldtypes": types,
        "fieldarraylen": lengths,
        "examples": examples,
        "constnames": constnames,
        "constvalues": constvalues,
    }


def _recursive(type_name: str, seen: list[str]) -> list[TypeDef]:
    if type_name in seen:
        return []
    seen.append(type_name)
    if type_name in ATOMICS:
        return []
    try:
        cls = message_class(type_name)
    except MessageError:
        return []  # not installed: stock logs it and leaves it out
    return _with_fields(typedef(cls), seen)


def _with_fields(root: TypeDef, seen: list[str]) -> list[TypeDef]:
    out = [root]
    for field_type in root["fieldtypes"]:
        out += _recursive(field_type, seen)
    return out


def message_typedefs(type_name: str) -> list[TypeDef]:
    """``message_details``: the type's TypeDef and those of the types it holds; [] when not installed."""
    return _recursive(type_name, [])


def service_typedefs(type_name: str, part: str) -> list[TypeDef]:
    """``service_request_details`` (``part`` Request) / ``service_response_details`` (Response);
    MessageError when the service type is not installed."""
    return _with_fields(typedef(getattr(service_class(type_name), part)), [])
