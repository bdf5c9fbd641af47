"""What rosbridge_suite's rosapi node answers, derived here from rclpy's own view (the message classes,
the graph), to compare a rosbridge server's answers with. rosapi's rules, as its ``objectutils`` and
``proxy`` apply them: a type is named ``pkg/Name`` (a service's parts ``pkg/Name_Request``), a field's
type is the IDL's (``double``, ``boolean``, ``string``, or ``pkg/Name``), its ``fieldarraylen`` -1
(no array), 0 (a sequence) or N (``T[N]``); the typedefs are the type's and then, depth first, each
field type's not yet listed; atomic types have none.

Field names are the message's (``get_fields_and_field_types``): rosapi 2.1.0 reads ``__slots__``,
which gives ``_x`` on Humble's classes and a ``KeyError('check_fields')`` on Jazzy's and later
(rosbridge_suite issue 976; its PR 854 reads the field names instead), so the TypeDef of a working
rosapi, ROS 1's, and what roslibjs's ``decodeTypeDefs`` needs, is what is expected here.

Compared: ``type``, ``fieldnames``, ``fieldtypes``, ``fieldarraylen``. Not compared: ``examples`` and
``constnames``/``constvalues``, where rosapi 2.1.0 shows Python's ``repr`` of a default and, on the
ROS 2 message classes, lists ``SLOT_TYPES`` and each field's accessor as constants.
"""

from __future__ import annotations

import importlib
import re
from typing import Any

from .waits import wait_for

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


def hidden(name: str) -> bool:
    return any(part.startswith("_") for part in name.split("/"))


class GraphTruth:
    """rclpy's own view of the graph (the peer's node), as rosapi reads it."""

    def __init__(self, node: Any) -> None:
        self.node = node  # an rclpy node whose executor spins in another thread

    def topics(self, include_hidden: bool = False) -> dict[str, str]:
        return {
            n: types[0]
            for n, types in self.node.get_topic_names_and_types()
            if include_hidden or not hidden(n)
        }

    def services(self) -> dict[str, str]:
        return {n: types[0] for n, types in self.node.get_service_names_and_types() if not hidden(n)}

    def nodes(self) -> list[str]:
        return sorted(
            (ns.rstrip("/") + "/" + name)
            for name, ns in self.node.get_node_names_and_namespaces()
            if not name.startswith("_")
        )

    def node_details(self, full_name: str) -> dict[str, list[str]]:
        ns, _, name = full_name.rpartition("/")
        ns = ns or "/"

        def names(pairs: list[tuple[str, list[str]]]) -> list[str]:
            return sorted(n for n, _ in pairs if not hidden(n))

        return {
            "subscribing": names(self.node.get_subscriber_names_and_types_by_node(name, ns)),
            "publishing": names(self.node.get_publisher_names_and_types_by_node(name, ns)),
            "services": names(self.node.get_service_names_and_types_by_node(name, ns)),
        }

    def param_names(self) -> list[str]:
        """Every node's parameters, ``<node>:<name>``, asked of its own list_parameters service."""
        from rcl_interfaces.srv import ListParameters

        services = self.services()
        found: list[str] = []
        for node in self.nodes():
            service = f"{node}/list_parameters"
            if services.get(service) != "rcl_interfaces/srv/ListParameters":
                continue  # a node without parameter services: rosapi lists nothing of it
            client = self.node.create_client(ListParameters, service)
            try:
                assert client.wait_for_service(timeout_sec=10), service
                future = client.call_async(ListParameters.Request())
                assert wait_for(future.done, 10), f"{service} did not answer"
                found += [f"{node}:{p}" for p in future.result().result.names]
            finally:
                self.node.destroy_client(client)
        return found

    def publishers(self, topic: str) -> list[str]:
        return sorted(
            {
                i.node_namespace.rstrip("/") + "/" + i.node_name
                for i in self.node.get_publishers_info_by_topic(topic)
            }
        )
