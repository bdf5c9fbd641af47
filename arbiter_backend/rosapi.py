"""rosapi: the services ``call_service`` reaches under ``/rosapi/``, what roslibjs dashboards and
Foxglove-style tools call to list topics, nodes, who publishes and subscribes a topic, the services,
the action servers, the message types and the parameters: the 24 services of rosbridge_suite's
``rosapi_msgs/srv``, with its request and response fields. One table per source, all built here:

- ``bus_handlers`` (both transports, from the endpoint's bus): ``topics`` → ``topics``, ``types``;
  ``topic_type`` (``topic``) → ``type`` (``""`` for a topic that is not there);
  ``topics_for_type`` (``type``) → ``topics``; ``get_ros_version`` → ``version`` (2), ``distro``;
  ``message_details`` (``type``) → ``typedefs`` for the types the embedded transport knows
  (``arbiter_core.msgtypes``; in ROS mode the graph's, below, for every installed type).
- ``handlers`` (``--transport ros``, from the live ROS graph), as rosbridge_suite's rosapi node
  answers: ``nodes`` → ``nodes``; ``node_details`` (``node``) → ``subscribing``, ``publishing``,
  ``services``; ``publishers`` / ``subscribers`` (``topic``) → ``publishers`` / ``subscribers`` (node
  names); ``services`` → ``services``; ``service_type`` (``service``) → ``type`` (``""`` for none);
  ``services_for_type`` (``type``) → ``services``; ``service_node`` (``service``) → ``node`` (the node
  that serves it, ``""`` for none); ``service_providers`` (``service``: a service TYPE, as the stock
  node reads it) → ``providers`` (the nodes serving one of that type); ``action_servers`` →
  ``action_servers`` (each action on the graph with its ``_action/feedback`` and ``_action/status``
  topics); ``get_time`` → ``time`` (``sec``, ``nanosec``); ``topics_and_raw_types`` → ``topics``,
  ``types``, ``typedefs_full_text`` (each type's ``.msg`` text with its dependencies', as ``gendeps
  --cat`` gives it); ``message_details`` (``type``) → ``typedefs``; ``service_request_details`` /
  ``service_response_details`` (``type``: a service type) → ``typedefs`` (rosapi's ``TypeDef`` form:
  ``ros/typedefs.py``). The embedded transport has no ROS graph: these are not offered there ("does
  not exist").
- the parameter services, over either store (``rosapi_params.py``).

Hidden names (a part starting with ``_``: action topics and services, ``_``-named nodes) are left out
of the lists, as the stock node leaves them out. A topic, service or node name in the arguments is
resolved as every name a client gives (``arbiter_core.topics.resolve``: ``odom`` is ``/odom`` for a
bridge in the root namespace); the stock node compares its arguments as given.

Each handler takes rosbridge ``args`` (an object keyed by the request's fields, or a list in their
order) and returns the response's fields, or an awaitable of them; ValueError says why not.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from typing import Any, Protocol

from arbiter_core import msgtypes
from arbiter_core.msgtypes import MessageError, normalize_type
from arbiter_core.topics import is_hidden
from arbiter_core.topics import stamp as ros_stamp

from .bus import Bus
from .rosapi_params import (
    PARAM_FIELDS,
    PARAM_TIMEOUT_S,
    GraphParams,
    Handler,
    Params,
    ParamStore,
    Resolve,
    arg,
    in_root,
    node_and_param,
    param_handlers,
    parameter_json,
    parameter_value,
)

__all__ = [
    "PARAM_FIELDS",
    "PARAM_TIMEOUT_S",
    "Graph",
    "GraphParams",
    "Handler",
    "ParamStore",
    "Params",
    "Resolve",
    "bus_handlers",
    "handlers",
    "node_and_param",
    "param_handlers",
    "parameter_json",
    "parameter_value",
]

ROS_VERSION = 2


class Graph(Protocol):
    """What a transport with a ROS graph can tell (``ros.graph.RosGraph``, the ROS bus's ``graph``)."""

    def node_names(self) -> list[str]: ...  # fully qualified: /ns/name

    def topic_endpoints(self, topic: str) -> tuple[list[str], list[str]]: ...  # (publishers, subscribers)

    def node_endpoints(self, node: str) -> tuple[list[str], list[str], list[str]]: ...  # (subs, pubs, srvs)

    def node_services(self, node: str) -> list[tuple[str, list[str]]]: ...  # (service, its types)

    def service_names_and_types(self) -> list[tuple[str, list[str]]]: ...

    def topics(self) -> list[tuple[str, str]]: ...

    def topic_names(self) -> list[str]: ...  # every topic on the graph, hidden ones too

    def typedef_text(self, type_name: str) -> str: ...  # the .msg text with its dependencies'

    def message_typedefs(self, type_name: str) -> list[dict[str, Any]]: ...  # rosapi TypeDefs

    def service_typedefs(self, type_name: str, part: str) -> list[dict[str, Any]]: ...

    def distro(self) -> str: ...  # the ROS 2 distribution of the installed rclpy ("kilted")

    async def call_service(self, service: str, args: Any) -> dict[str, Any]: ...


def ros_version(distro: str = "") -> dict[str, Any]:
    """``get_ros_version``: ROS 2, the distribution from ``ROS_DISTRO`` as stock (else ``distro``)."""
    return {"version": ROS_VERSION, "distro": os.environ.get("ROS_DISTRO") or distro}


def bus_handlers(
    bus: Bus,
    topic_ok: Callable[[str], bool] = lambda name: True,
    resolve: Resolve = in_root,
    distro: str = "",
) -> dict[str, Handler]:
    """``/rosapi/topics``, ``topic_type``, ``topics_for_type``, ``get_ros_version`` and
    ``message_details`` from the endpoint's bus (either transport); nothing outside ``topic_ok``
    (--topics-glob) appears."""

    def topics(args: Any) -> dict[str, Any]:
        listed = [(t, ty) for t, ty in bus.topics() if topic_ok(t) and not is_hidden(t)]
        return {"topics": [t for t, _ in listed], "types": [ty for _, ty in listed]}

    def topic_type(args: Any) -> dict[str, Any]:
        topic = resolve(arg(args, "topic"), "topic")
        return {"type": (bus.type_of(topic) or "") if topic_ok(topic) and not is_hidden(topic) else ""}

    def topics_for_type(args: Any) -> dict[str, Any]:
        want = normalize_type(arg(args, "type"))
        return {"topics": [t for t, ty in bus.topics() if ty == want and topic_ok(t) and not is_hidden(t)]}

    return {
        "/rosapi/topics": topics,
        "/rosapi/topic_type": topic_type,
        "/rosapi/topics_for_type": topics_for_type,
        "/rosapi/get_ros_version": lambda args: ros_version(distro),
        # the types the embedded transport knows (in ROS mode the graph's handler, every installed type)
        "/rosapi/message_details": lambda args: {"typedefs": msgtypes.typedefs(arg(args, "type"))},
    }


def action_servers(topics: list[str]) -> list[str]:
    """The actions whose servers a topic list shows (stock: an action with both its
    ``<name>/_action/feedback`` and ``<name>/_action/status`` topics), sorted."""
    ends: dict[str, set[str]] = {}
    for topic in topics:
        prefix, sep, last = topic.rpartition("/_action/")
        if sep and prefix.strip("/") and last in ("feedback", "status"):
            ends.setdefault(prefix, set()).add(last)
    return sorted(name for name, got in ends.items() if len(got) == 2)


def handlers(
    graph: Graph,
    clock_ns: Callable[[], int] = time.time_ns,
    topic_ok: Callable[[str], bool] = lambda name: True,
    service_ok: Callable[[str], bool] = lambda name: True,
    param_ok: Callable[[str], bool] = lambda name: True,
    resolve: Resolve = in_root,
) -> dict[str, Handler]:
    """The rosapi services over ``graph``, by service name; nothing outside what the server exposes
    (``topic_ok``, ``service_ok``: its --topics-glob and --services-glob) appears in an answer; the
    names in the arguments resolved with ``resolve``."""

    def named(args: Any, key: str) -> str:
        return resolve(arg(args, key), key)

    def service_list() -> list[tuple[str, list[str]]]:
        return [(n, ts) for n, ts in graph.service_names_and_types() if service_ok(n) and not is_hidden(n)]

    def nodes() -> list[str]:  # hidden: a node whose own name starts with _ (ros2node's rule)
        return sorted({n for n in graph.node_names() if not n.rpartition("/")[2].startswith("_")})

    def node_details(args: Any) -> dict[str, Any]:
        node = named(args, "node")
        if node not in graph.node_names():
            raise ValueError(f"no node {node} on the graph")
        subs, pubs, srvs = graph.node_endpoints(node)
        return {
            "subscribing": sorted(t for t in subs if topic_ok(t) and not is_hidden(t)),
            "publishing": sorted(t for t in pubs if topic_ok(t) and not is_hidden(t)),
            "services": sorted(x for x in srvs if service_ok(x) and not is_hidden(x)),
        }

    def endpoints(args: Any, which: int) -> list[str]:
        topic = named(args, "topic")
        return sorted(set(graph.topic_endpoints(topic)[which])) if topic_ok(topic) else []

    def service_type(args: Any) -> dict[str, Any]:
        types = dict(service_list()).get(named(args, "service"))
        return {"type": types[0] if types else ""}

    def serving(wanted: Callable[[str, list[str]], bool]) -> list[str]:
        return [node for node in nodes() if any(wanted(s, ts) for s, ts in graph.node_services(node))]

    def service_node(args: Any) -> dict[str, Any]:
        service = named(args, "service")
        found = serving(lambda s, ts: s == service) if service_ok(service) else []
        return {"node": found[0] if found else ""}

    def service_providers(args: Any) -> dict[str, Any]:
        wanted = arg(args, "service")  # a type, as the stock node compares it
        return {"providers": serving(lambda s, ts: service_ok(s) and bool(ts) and ts[0] == wanted)}

    def topics_and_raw_types(args: Any) -> dict[str, Any]:
        topics = [(t, ty) for t, ty in graph.topics() if topic_ok(t) and not is_hidden(t)]
        return {
            "topics": [t for t, _ in topics],
            "types": [ty for _, ty in topics],
            "typedefs_full_text": [graph.typedef_text(ty) for _, ty in topics],
        }

    def service_details(args: Any, part: str) -> dict[str, Any]:
        try:
            return {"typedefs": graph.service_typedefs(arg(args, "type"), part)}
        except MessageError as exc:
            raise ValueError(str(exc)) from None

    return {
        "/rosapi/nodes": lambda args: {"nodes": nodes()},
        "/rosapi/node_details": node_details,
        "/rosapi/publishers": lambda args: {"publishers": endpoints(args, 0)},
        "/rosapi/subscribers": lambda args: {"subscribers": endpoints(args, 1)},
        "/rosapi/services": lambda args: {"services": sorted(n for n, _ in service_list())},
        "/rosapi/service_type": service_type,
        "/rosapi/services_for_type": lambda args: {
            "services": sorted(n for n, ts in service_list() if arg(args, "type") in ts)
        },
        "/rosapi/service_node": service_node,
        "/rosapi/service_providers": service_providers,
        "/rosapi/action_servers": lambda args: {
            "action_servers": action_servers([t for t in graph.topic_names() if topic_ok(t)])
        },
        "/rosapi/get_time": lambda args: {"time": ros_stamp(clock_ns())},
        "/rosapi/get_ros_version": lambda args: ros_version(graph.distro()),
        "/rosapi/topics_and_raw_types": topics_and_raw_types,
        "/rosapi/message_details": lambda args: {"typedefs": graph.message_typedefs(arg(args, "type"))},
        "/rosapi/service_request_details": lambda args: service_details(args, "Request"),
        "/rosapi/service_response_details": lambda args: service_details(args, "Response"),
        **param_handlers(GraphParams(graph, service_ok, param_ok, resolve)),
    }
