"""rosapi: the services ``call_service`` reaches under ``/rosapi/``, what roslibjs dashboards and
Foxglove-style tools call to list topics, nodes, who publishes and subscribes a topic, the services,
and the parameters. One table per source, all in this module:

- ``bus_handlers`` (both transports, from the endpoint's bus): ``/rosapi/topics`` → ``topics``,
  ``types``; ``/rosapi/topic_type`` → ``type``; ``/rosapi/topics_for_type`` → ``topics``.
- ``handlers`` (``--transport ros``, from the live ROS graph), as rosbridge_suite's rosapi node
  answers: ``/rosapi/nodes`` → ``nodes``; ``/rosapi/node_details`` → ``subscribing``, ``publishing``,
  ``services``; ``/rosapi/publishers`` and ``/rosapi/subscribers`` → ``publishers``/``subscribers``
  (node names); ``/rosapi/services`` → ``services``; ``/rosapi/service_type`` → ``type``;
  ``/rosapi/services_for_type`` → ``services``; ``/rosapi/get_time`` → ``time`` (``sec``,
  ``nanosec``); ``/rosapi/topics_and_raw_types`` → ``topics``, ``types``, ``typedefs_full_text``
  (each type's ``.msg`` text with its dependencies', as ``gendeps --cat`` gives it, for ``cbor-raw``
  clients). The embedded transport has no ROS graph: these are not offered there ("does not exist").
- ``param_handlers``, one table over either store of parameters, as roslibjs and roslibpy's ``Param``
  call them (rosapi's ROS 2 names, ``<node>:<param>``): ``/rosapi/get_param`` (``name``,
  ``default_value``: JSON text) → ``value`` (JSON text; the default when the node or parameter does not
  exist), ``/rosapi/set_param`` (``name``, ``value``: JSON text), ``/rosapi/has_param`` → ``exists``,
  ``/rosapi/delete_param``, ``/rosapi/get_param_names`` → ``names`` (every node's, ``<node>:<param>``).
  In ROS mode (``GraphParams``) they call the node's own parameter services (``get_parameters``,
  ``set_parameters``, ``list_parameters``); a set or delete the node refuses is ``result: false`` with
  its reason (rosapi says nothing). On the embedded transport there are no nodes: the same services
  keep plain names in a store in memory, for the backend's lifetime (``ParamStore``). ``--params-glob``
  bounds both by parameter name (outside it: result false, not there, not listed).

Each handler takes rosbridge ``args`` (an object keyed by the request's fields, or a list in their
order) and returns the response's fields, or an awaitable of them; ValueError says why not.
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Callable
from typing import Any, Protocol

from arbiter_core.msgtypes import normalize_type
from arbiter_core.topics import stamp as ros_stamp

from .bus import Bus

Handler = Callable[[Any], Any]  # the response's fields, or an awaitable of them
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
    """What a transport with a ROS graph can tell (``ros.graph.RosGraph``, the ROS bus's ``graph``)."""

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


def bus_handlers(bus: Bus, topic_ok: Callable[[str], bool] = lambda name: True) -> dict[str, Handler]:
    """``/rosapi/topics``, ``topic_type`` and ``topics_for_type`` from the endpoint's bus (either
    transport); nothing outside ``topic_ok`` (--topics-glob) appears."""

    def topics(args: Any) -> dict[str, Any]:
        listed = [(t, ty) for t, ty in bus.topics() if topic_ok(t)]
        return {"topics": [t for t, _ in listed], "types": [ty for _, ty in listed]}

    def topic_type(args: Any) -> dict[str, Any]:
        topic = (
            args.get("topic")
            if isinstance(args, dict)
            else (args[0] if isinstance(args, list) and args else None)
        )
        if not isinstance(topic, str):
            raise ValueError("args.topic must be a string")
        return {"type": (bus.type_of(topic) or "") if topic_ok(topic) else ""}

    def topics_for_type(args: Any) -> dict[str, Any]:
        t = args.get("type") if isinstance(args, dict) else None
        if not isinstance(t, str):
            raise ValueError("args.type must be a string")
        want = normalize_type(t)
        return {"topics": [t for t, ty in bus.topics() if ty == want and topic_ok(t)]}

    return {
        "/rosapi/topics": topics,
        "/rosapi/topic_type": topic_type,
        "/rosapi/topics_for_type": topics_for_type,
    }


def param_handlers(params: Params) -> dict[str, Handler]:
    """The parameter services, as rosapi names them, over either store; the arguments are read here,
    the store answers (at once in memory, an awaitable on the graph)."""
    return {
        "/rosapi/get_param": lambda args: params.get(_arg(args, "name"), _json_arg(args, "default_value", 1)),
        "/rosapi/set_param": lambda args: params.set(_arg(args, "name"), _json_arg(args, "value", 1)),
        "/rosapi/has_param": lambda args: params.has(_arg(args, "name")),
        "/rosapi/delete_param": lambda args: params.delete(_arg(args, "name")),
        "/rosapi/get_param_names": lambda args: params.names(),
    }


class Params(Protocol):
    """Where the parameters are: each answer is the rosapi response's fields (or an awaitable of them);
    ValueError says why not. ``default``, ``value``: JSON values (None: none given)."""

    def get(self, name: str, default: Any) -> Any: ...

    def set(self, name: str, value: Any) -> Any: ...

    def has(self, name: str) -> Any: ...

    def delete(self, name: str) -> Any: ...

    def names(self) -> Any: ...


class ParamStore:
    """The parameters on the embedded transport: plain names, values kept in memory."""

    def __init__(self) -> None:
        self.values: dict[str, Any] = {}
        self.param_ok: Callable[[str], bool] = lambda name: True

    def handlers(self, param_ok: Callable[[str], bool] = lambda name: True) -> dict[str, Handler]:
        """``param_ok``: the server's --params-glob (outside it: result false; not listed, not there)."""
        self.param_ok = param_ok
        return param_handlers(self)

    def get(self, name: str, default: Any) -> dict[str, Any]:
        name = _exposed(self.param_ok, name)
        return {"value": json.dumps(self.values.get(name, "" if default is None else default))}

    def set(self, name: str, value: Any) -> dict[str, Any]:
        name = _exposed(self.param_ok, name)
        parameter_value(value)  # the kinds a ROS parameter can hold, as on the graph
        self.values[name] = value
        return {}

    def has(self, name: str) -> dict[str, Any]:
        return {"exists": self.param_ok(name) and name in self.values}

    def delete(self, name: str) -> dict[str, Any]:
        self.values.pop(_exposed(self.param_ok, name), None)
        return {}

    def names(self) -> dict[str, Any]:
        return {"names": sorted(n for n in self.values if self.param_ok(n))}


class GraphParams:
    """The parameters of the nodes on the graph, through their own parameter services (ROS mode); a
    node whose parameter services are outside --services-glob is as if it had none; a parameter whose
    name (the part after ``<node>:``, as rosapi matches params_glob) is outside --params-glob is not
    reachable."""

    def __init__(
        self,
        graph: Graph,
        service_ok: Callable[[str], bool] = lambda name: True,
        param_ok: Callable[[str], bool] = lambda name: True,
    ) -> None:
        self.graph = graph
        self.service_ok = service_ok
        self.param_ok = param_ok

    async def get(self, name: str, default: Any) -> dict[str, Any]:
        found, value = await self._fetch(name)
        return {"value": json.dumps(value if found else ("" if default is None else default))}

    async def set(self, name: str, value: Any) -> dict[str, Any]:
        return await self._change(name, parameter_value(value))

    async def has(self, name: str) -> dict[str, Any]:
        if not self.param_ok(node_and_param(name)[1]):
            return {"exists": False}
        return {"exists": (await self._fetch(name))[0]}

    async def delete(self, name: str) -> dict[str, Any]:
        return await self._change(name, {"type": 0})

    async def names(self) -> dict[str, Any]:
        found = await asyncio.gather(*(self._names_of(node) for node in sorted(set(self.graph.node_names()))))
        return {"names": [name for names in found for name in names]}

    async def _call(self, node: str, service: str, args: dict[str, Any]) -> dict[str, Any]:
        name = f"{node}/{service}"
        if not self.service_ok(name):
            raise ValueError(f"service {name} is not exposed by this server (--services-glob)")
        return await self.graph.call_service(name, args)

    async def _fetch(self, name: str) -> tuple[bool, Any]:
        node, param = node_and_param(name)
        _exposed(self.param_ok, param)
        try:
            got = await self._call(node, "get_parameters", {"names": [param]})
        except (ValueError, TimeoutError, asyncio.TimeoutError):
            return False, None  # no such node (rosapi: the default)
        values = got.get("values") or [{}]
        return parameter_json(values[0])

    async def _change(self, name: str, value: dict[str, Any]) -> dict[str, Any]:
        node, param = node_and_param(name)
        _exposed(self.param_ok, param)
        got = await self._call(node, "set_parameters", {"parameters": [{"name": param, "value": value}]})
        result = (got.get("results") or [{}])[0]
        if not result.get("successful", False):
            raise ValueError(f"{node} refused: {result.get('reason') or 'no reason given'}")
        return {}

    async def _names_of(self, node: str) -> list[str]:
        try:
            got = await asyncio.wait_for(self._call(node, "list_parameters", {}), PARAM_TIMEOUT_S)
        except (ValueError, TimeoutError, asyncio.TimeoutError):
            return []  # a node without parameter services (or not answering)
        return [f"{node}:{p}" for p in got.get("result", {}).get("names", []) if self.param_ok(p)]


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
        **param_handlers(GraphParams(graph, service_ok, param_ok)),
    }
