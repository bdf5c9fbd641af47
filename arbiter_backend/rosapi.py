"""rosapi services answered from the live ROS graph (``--transport ros``): what roslibjs dashboards and
Foxglove-style tools call to list nodes, who publishes and subscribes a topic, and the services.

Each handler takes rosbridge ``args`` (an object keyed by the rosapi request's fields, or a list in
their order) and returns the rosapi response's fields, as rosbridge_suite's rosapi node does:
``/rosapi/nodes`` → ``nodes``; ``/rosapi/node_details`` → ``subscribing``, ``publishing``,
``services``; ``/rosapi/publishers`` and ``/rosapi/subscribers`` → ``publishers``/``subscribers``
(node names); ``/rosapi/services`` → ``services``; ``/rosapi/service_type`` → ``type``;
``/rosapi/services_for_type`` → ``services``; ``/rosapi/get_time`` → ``time`` (``sec``, ``nanosec``);
``/rosapi/topics_and_raw_types`` → ``topics``, ``types``, ``typedefs_full_text`` (each type's ``.msg``
text with its dependencies', as ``gendeps --cat`` gives it, for ``cbor-raw`` clients).
The embedded transport has no ROS graph: these are not offered there (a call is "does not exist").

Parameters, as roslibjs and roslibpy's ``Param`` call them (rosapi's ROS 2 names, ``<node>:<param>``):
``/rosapi/get_param`` (``name``, ``default_value``: JSON text) → ``value`` (JSON text; the default when
the node or parameter does not exist), ``/rosapi/set_param`` (``name``, ``value``: JSON text),
``/rosapi/has_param`` → ``exists``, ``/rosapi/delete_param``, ``/rosapi/get_param_names`` → ``names``
(every node's, ``<node>:<param>``). In ROS mode they call the node's own parameter services
(``get_parameters``, ``set_parameters``, ``list_parameters``); a set or delete the node refuses is
``result: false`` with its reason (rosapi says nothing). On the embedded transport there are no nodes:
the same services keep plain names in a store in memory, for the backend's lifetime (``ParamStore``).
``--params-glob`` bounds both by parameter name (outside it: result false, not there, not listed).
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Awaitable, Callable
from typing import Any, Protocol

from arbiter_core.topics import stamp as ros_stamp

Handler = Callable[[Any], Any]  # the response's fields, or an awaitable of them
Call = Callable[[str, Any], Awaitable[dict[str, Any]]]  # a ROS service call (RosBus.call_service)
PARAM_TIMEOUT_S = 2.0  # one node's parameter service, for get_param_names (a node that hangs is skipped)

# rcl_interfaces/msg/ParameterType -> the ParameterValue field holding it
PARAM_FIELDS = {
    1: "bool_value",
    2: "integer_value",
    3: "double_value",
    4: "string_value",
    5: "byte_array_value",
    6: "bool_array_value",
    7: "integer_array_value",
    8: "double_array_value",
    9: "string_array_value",
}


class Graph(Protocol):
    """What a transport with a ROS graph can tell (``ros.bus.RosBus``)."""

    def node_names(self) -> list[str]: ...  # fully qualified: /ns/name

    def topic_endpoints(self, topic: str) -> tuple[list[str], list[str]]: ...  # (publishers, subscribers)

    def node_endpoints(self, node: str) -> tuple[list[str], list[str], list[str]]: ...  # (subs, pubs, srvs)

    def service_names_and_types(self) -> list[tuple[str, list[str]]]: ...

    def topics(self) -> list[tuple[str, str]]: ...

    def typedef_text(self, type_name: str) -> str: ...  # the .msg text with its dependencies'

    async def call_service(self, service: str, args: Any) -> dict[str, Any]: ...


def _arg(args: Any, name: str, position: int = 0, empty: bool = False) -> str:
    value = (
        args.get(name, "" if empty else None)
        if isinstance(args, dict)
        else (args[position] if isinstance(args, list) and len(args) > position else None)
    )
    if not isinstance(value, str) or not (value or empty):
        raise ValueError(f"args.{name} must be a{'' if empty else ' non-empty'} string")
    return value


def _json_arg(args: Any, name: str, position: int) -> Any:
    """A value given as JSON text (rosapi's ``value``, ``default_value``); ``""``: None."""
    text = _arg(args, name, position, empty=True)
    if text == "":
        return None
    try:
        return json.loads(text)
    except ValueError:
        raise ValueError(f"args.{name} must be JSON text, e.g. '1.5', 'true', '\"text\"'") from None


def node_and_param(name: str) -> tuple[str, str]:
    """rosapi's ROS 2 parameter names: ``<node>:<param>`` (the node absolute or not)."""
    node, sep, param = name.partition(":")
    if not sep or not node or not param:
        raise ValueError(f"parameter name {name[:80]!r}: expecting <node_name>:<param_name>")
    return (node if node.startswith("/") else "/" + node), param


def parameter_value(value: Any) -> dict[str, Any]:
    """A JSON value as an rcl_interfaces/ParameterValue (rosbridge JSON form)."""
    if isinstance(value, bool):
        return {"type": 1, "bool_value": value}
    if isinstance(value, int):
        return {"type": 2, "integer_value": value}
    if isinstance(value, float):
        return {"type": 3, "double_value": value}
    if isinstance(value, str):
        return {"type": 4, "string_value": value}
    if isinstance(value, list) and value:
        if all(isinstance(v, bool) for v in value):
            return {"type": 6, "bool_array_value": value}
        if all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            return {"type": 7, "integer_array_value": value}
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            return {"type": 8, "double_array_value": [float(v) for v in value]}
        if all(isinstance(v, str) for v in value):
            return {"type": 9, "string_array_value": value}
    raise ValueError("a parameter is a bool, number, string, or a non-empty list of one of them")


def parameter_json(pv: dict[str, Any]) -> tuple[bool, Any]:
    """(set, value) of an rcl_interfaces/ParameterValue in rosbridge JSON form."""
    field = PARAM_FIELDS.get(pv.get("type", 0))
    return (False, None) if field is None else (True, pv.get(field))


def _exposed(param_ok: Callable[[str], bool], param: str) -> str:
    if not param_ok(param):
        raise ValueError(f"parameter {param} is not exposed by this server (--params-glob)")
    return param


class ParamStore:
    """The parameter services on the embedded transport: plain names, values kept in memory."""

    def __init__(self) -> None:
        self.values: dict[str, Any] = {}

    def handlers(self, param_ok: Callable[[str], bool] = lambda name: True) -> dict[str, Handler]:
        """``param_ok``: the server's --params-glob (outside it: result false; not listed, not there)."""

        def get_param(args: Any) -> dict[str, Any]:
            name = _exposed(param_ok, _arg(args, "name"))
            default = _json_arg(args, "default_value", 1)
            return {"value": json.dumps(self.values.get(name, "" if default is None else default))}

        def set_param(args: Any) -> dict[str, Any]:
            name, value = _exposed(param_ok, _arg(args, "name")), _json_arg(args, "value", 1)
            parameter_value(value)  # the kinds a ROS parameter can hold, as on the graph
            self.values[name] = value
            return {}

        def has_param(args: Any) -> dict[str, Any]:
            name = _arg(args, "name")
            return {"exists": param_ok(name) and name in self.values}

        def delete_param(args: Any) -> dict[str, Any]:
            self.values.pop(_exposed(param_ok, _arg(args, "name")), None)
            return {}

        def get_param_names(args: Any) -> dict[str, Any]:
            return {"names": sorted(n for n in self.values if param_ok(n))}

        return {
            "/rosapi/get_param": get_param,
            "/rosapi/set_param": set_param,
            "/rosapi/has_param": has_param,
            "/rosapi/delete_param": delete_param,
            "/rosapi/get_param_names": get_param_names,
        }


def param_handlers(
    graph: Graph,
    service_ok: Callable[[str], bool] = lambda name: True,
    param_ok: Callable[[str], bool] = lambda name: True,
) -> dict[str, Handler]:
    """The parameter services over the nodes' own parameter services (ROS mode); a node whose
    parameter services are outside --services-glob is as if it had none; a parameter whose name (the
    part after ``<node>:``, as rosapi matches params_glob) is outside --params-glob is not reachable."""

    async def call(node: str, service: str, args: dict[str, Any]) -> dict[str, Any]:
        name = f"{node}/{service}"
        if not service_ok(name):
            raise ValueError(f"service {name} is not exposed by this server (--services-glob)")
        return await graph.call_service(name, args)

    async def fetch(name: str) -> tuple[bool, Any]:
        node, param = node_and_param(name)
        _exposed(param_ok, param)
        try:
            got = await call(node, "get_parameters", {"names": [param]})
        except (ValueError, TimeoutError, asyncio.TimeoutError):
            return False, None  # no such node (rosapi: the default)
        values = got.get("values") or [{}]
        return parameter_json(values[0])

    async def change(name: str, value: dict[str, Any]) -> dict[str, Any]:
        node, param = node_and_param(name)
        _exposed(param_ok, param)
        got = await call(node, "set_parameters", {"parameters": [{"name": param, "value": value}]})
        result = (got.get("results") or [{}])[0]
        if not result.get("successful", False):
            raise ValueError(f"{node} refused: {result.get('reason') or 'no reason given'}")
        return {}

    async def get_param(args: Any) -> dict[str, Any]:
        default = _json_arg(args, "default_value", 1)
        found, value = await fetch(_arg(args, "name"))
        return {"value": json.dumps(value if found else ("" if default is None else default))}

    async def set_param(args: Any) -> dict[str, Any]:
        return await change(_arg(args, "name"), parameter_value(_json_arg(args, "value", 1)))

    async def has_param(args: Any) -> dict[str, Any]:
        name = _arg(args, "name")
        if not param_ok(node_and_param(name)[1]):
            return {"exists": False}
        return {"exists": (await fetch(name))[0]}

    async def delete_param(args: Any) -> dict[str, Any]:
        return await change(_arg(args, "name"), {"type": 0})

    async def names_of(node: str) -> list[str]:
        try:
            got = await asyncio.wait_for(call(node, "list_parameters", {}), PARAM_TIMEOUT_S)
        except (ValueError, TimeoutError, asyncio.TimeoutError):
            return []  # a node without parameter services (or not answering)
        return [f"{node}:{p}" for p in got.get("result", {}).get("names", []) if param_ok(p)]

    async def get_param_names(args: Any) -> dict[str, Any]:
        found = await asyncio.gather(*(names_of(node) for node in sorted(set(graph.node_names()))))
        return {"names": [name for names in found for name in names]}

    return {
        "/rosapi/get_param": get_param,
        "/rosapi/set_param": set_param,
        "/rosapi/has_param": has_param,
        "/rosapi/delete_param": delete_param,
        "/rosapi/get_param_names": get_param_names,
    }


def handlers(
    graph: Graph,
    clock_ns: Callable[[], int] = time.time_ns,
    topic_ok: Callable[[str], bool] = lambda name: True,
    service_ok: Callable[[str], bool] = lambda name: True,
    param_ok: Callable[[str], bool] = lambda name: True,
) -> dict[str, Handler]:
    """The rosapi services over ``graph``, by service name; nothing outside what the server exposes
    (``topic_ok``, ``service_ok``: its --topics-glob and --services-glob) appears in an answer."""

    def exposed_topic(args: Any) -> str:
        topic = _arg(args, "topic")
        if not topic_ok(topic):
            raise ValueError(f"topic {topic} is not exposed by this server")
        return topic

    def service_list() -> list[tuple[str, list[str]]]:
        return [(n, types) for n, types in graph.service_names_and_types() if service_ok(n)]

    def nodes(args: Any) -> dict[str, Any]:
        return {"nodes": sorted(graph.node_names())}

    def node_details(args: Any) -> dict[str, Any]:
        node = _arg(args, "node")
        if node not in graph.node_names():
            raise ValueError(f"no node {node} on the graph")
        subs, pubs, srvs = graph.node_endpoints(node)
        return {
            "subscribing": sorted(t for t in subs if topic_ok(t)),
            "publishing": sorted(t for t in pubs if topic_ok(t)),
            "services": sorted(x for x in srvs if service_ok(x)),
        }

    def publishers(args: Any) -> dict[str, Any]:
        return {"publishers": sorted(set(graph.topic_endpoints(exposed_topic(args))[0]))}

    def subscribers(args: Any) -> dict[str, Any]:
        return {"subscribers": sorted(set(graph.topic_endpoints(exposed_topic(args))[1]))}

    def services(args: Any) -> dict[str, Any]:
        return {"services": sorted(name for name, _types in service_list())}

    def service_type(args: Any) -> dict[str, Any]:
        service = _arg(args, "service")
        types = dict(service_list()).get(service)
        if not types:
            raise ValueError(f"no service {service} on the graph")
        return {"type": types[0]}

    def services_for_type(args: Any) -> dict[str, Any]:
        wanted = _arg(args, "type")
        return {"services": sorted(n for n, types in service_list() if wanted in types)}

    def get_time(args: Any) -> dict[str, Any]:
        now = clock_ns()
        return {"time": ros_stamp(now)}

    def topics_and_raw_types(args: Any) -> dict[str, Any]:
        topics = [(t, ty) for t, ty in graph.topics() if topic_ok(t)]
        return {
            "topics": [t for t, _ in topics],
            "types": [ty for _, ty in topics],
            "typedefs_full_text": [graph.typedef_text(ty) for _, ty in topics],
        }

    return {
        "/rosapi/nodes": nodes,
        "/rosapi/node_details": node_details,
        "/rosapi/publishers": publishers,
        "/rosapi/subscribers": subscribers,
        "/rosapi/services": services,
        "/rosapi/service_type": service_type,
        "/rosapi/services_for_type": services_for_type,
        "/rosapi/get_time": get_time,
        "/rosapi/topics_and_raw_types": topics_and_raw_types,
        **param_handlers(graph, service_ok, param_ok),
    }
