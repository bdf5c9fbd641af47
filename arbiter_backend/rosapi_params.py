"""rosapi's parameter services, as roslibjs and roslibpy's ``Param`` call them (rosapi's ROS 2 names,
``<node>:<param>``), over either store of parameters: ``/rosapi/get_param`` (``name``,
``default_value``: JSON text) → ``value`` (JSON text; the default when the node or parameter does not
exist), ``/rosapi/set_param`` (``name``, ``value``: JSON text), ``/rosapi/has_param`` → ``exists``,
``/rosapi/delete_param``, ``/rosapi/get_param_names`` → ``names`` (every node's, ``<node>:<param>``).
In ROS mode (``GraphParams``) they call the node's own parameter services (``get_parameters``,
``set_parameters``, ``list_parameters``); a set or delete the node refuses is ``result: false`` with
its reason (rosapi says nothing). On the embedded transport there are no nodes: the same services
keep plain names in a store in memory, for the backend's lifetime (``ParamStore``). ``--params-glob``
bounds both by parameter name (outside it: result false, not there, not listed). A relative node name
resolves under the bridge's namespace, as every name a client gives (``arbiter_core.topics.resolve``).
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import Callable
from typing import Any, Protocol

from arbiter_core import topics

Handler = Callable[[Any], Any]  # the response's fields, or an awaitable of them
Resolve = Callable[[str, str], str]  # (a name a client gave, what it names) -> the name resolved
PARAM_TIMEOUT_S = 2.0  # one node's parameter service, for get_param_names (a node that hangs is skipped)


def in_root(name: str, what: str) -> str:
    """A name resolved for a bridge in the root namespace (the default ``Resolve``)."""
    return topics.resolve(name, "", what=what, node=topics.BRIDGE_NODE)


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


def arg(args: Any, name: str, position: int = 0, empty: bool = False) -> str:
    value = (
        args.get(name, "" if empty else None)
        if isinstance(args, dict)
        else (args[position] if isinstance(args, list) and len(args) > position else None)
    )
    if not isinstance(value, str) or not (value or empty):
        raise ValueError(f"args.{name} must be a{'' if empty else ' non-empty'} string")
    return value


def json_arg(args: Any, name: str, position: int) -> Any:
    """A value given as JSON text (rosapi's ``value``, ``default_value``); ``""``: None."""
    text = arg(args, name, position, empty=True)
    if text == "":
        return None
    try:
        return json.loads(text)
    except ValueError:
        raise ValueError(f"args.{name} must be JSON text, e.g. '1.5', 'true', '\"text\"'") from None


def node_and_param(name: str, resolve: Resolve = in_root) -> tuple[str, str]:
    """rosapi's ROS 2 parameter names: ``<node>:<param>`` (the node absolute or relative)."""
    node, sep, param = name.partition(":")
    if not sep or not node or not param:
        raise ValueError(f"parameter name {name[:80]!r}: expecting <node_name>:<param_name>")
    return resolve(node, "node"), param


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


def param_handlers(params: Params) -> dict[str, Handler]:
    """The parameter services, as rosapi names them, over either store; the arguments are read here,
    the store answers (at once in memory, an awaitable on the graph)."""
    return {
        "/rosapi/get_param": lambda args: params.get(arg(args, "name"), json_arg(args, "default_value", 1)),
        "/rosapi/set_param": lambda args: params.set(arg(args, "name"), json_arg(args, "value", 1)),
        "/rosapi/has_param": lambda args: params.has(arg(args, "name")),
        "/rosapi/delete_param": lambda args: params.delete(arg(args, "name")),
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


class ParamGraph(Protocol):
    """What the parameters of the graph's nodes need of it (``rosapi.Graph`` has it)."""

    def node_names(self) -> list[str]: ...

    async def call_service(self, service: str, args: Any) -> dict[str, Any]: ...


class GraphParams:
    """The parameters of the nodes on the graph, through their own parameter services (ROS mode); a
    node whose parameter services are outside --services-glob is as if it had none; a parameter whose
    name (the part after ``<node>:``, as rosapi matches params_glob) is outside --params-glob is not
    reachable."""

    def __init__(
        self,
        graph: ParamGraph,
        service_ok: Callable[[str], bool] = lambda name: True,
        param_ok: Callable[[str], bool] = lambda name: True,
        resolve: Resolve = in_root,
    ) -> None:
        self.graph = graph
        self.service_ok = service_ok
        self.param_ok = param_ok
        self.resolve = resolve

    async def get(self, name: str, default: Any) -> dict[str, Any]:
        found, value = await self._fetch(name)
        return {"value": json.dumps(value if found else ("" if default is None else default))}

    async def set(self, name: str, value: Any) -> dict[str, Any]:
        return await self._change(name, parameter_value(value))

    async def has(self, name: str) -> dict[str, Any]:
        if not self.param_ok(node_and_param(name, self.resolve)[1]):
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
        node, param = node_and_param(name, self.resolve)
        _exposed(self.param_ok, param)
        try:
            got = await self._call(node, "get_parameters", {"names": [param]})
        except (ValueError, TimeoutError, asyncio.TimeoutError):
            return False, None  # no such node (rosapi: the default)
        values = got.get("values") or [{}]
        return parameter_json(values[0])

    async def _change(self, name: str, value: dict[str, Any]) -> dict[str, Any]:
        node, param = node_and_param(name, self.resolve)
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
