"""rosapi services answered from the live ROS graph (``--transport ros``): what roslibjs dashboards and
Foxglove-style tools call to list nodes, who publishes and subscribes a topic, and the services.

Each handler takes rosbridge ``args`` (an object keyed by the rosapi request's fields, or a list in
their order) and returns the rosapi response's fields, as rosbridge_suite's rosapi node does:
``/rosapi/nodes`` → ``nodes``; ``/rosapi/node_details`` → ``subscribing``, ``publishing``,
``services``; ``/rosapi/publishers`` and ``/rosapi/subscribers`` → ``publishers``/``subscribers``
(node names); ``/rosapi/services`` → ``services``; ``/rosapi/service_type`` → ``type``;
``/rosapi/services_for_type`` → ``services``; ``/rosapi/get_time`` → ``time`` (``sec``, ``nanosec``).
The embedded transport has no ROS graph: these are not offered there (a call is "does not exist").
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, Protocol

Handler = Callable[[Any], dict[str, Any]]


class Graph(Protocol):
    """What a transport with a ROS graph can tell (``ros.bus.RosBus``)."""

    def node_names(self) -> list[str]: ...  # fully qualified: /ns/name

    def topic_endpoints(self, topic: str) -> tuple[list[str], list[str]]: ...  # (publishers, subscribers)

    def node_endpoints(self, node: str) -> tuple[list[str], list[str], list[str]]: ...  # (subs, pubs, srvs)

    def service_names_and_types(self) -> list[tuple[str, list[str]]]: ...


def _arg(args: Any, name: str, position: int = 0) -> str:
    value = (
        args.get(name)
        if isinstance(args, dict)
        else (args[position] if isinstance(args, list) and args else None)
    )
    if not isinstance(value, str) or not value:
        raise ValueError(f"args.{name} must be a non-empty string")
    return value


def handlers(
    graph: Graph,
    clock_ns: Callable[[], int] = time.time_ns,
    topic_ok: Callable[[str], bool] = lambda name: True,
    service_ok: Callable[[str], bool] = lambda name: True,
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
        return {"time": {"sec": now // 1_000_000_000, "nanosec": now % 1_000_000_000}}

    return {
        "/rosapi/nodes": nodes,
        "/rosapi/node_details": node_details,
        "/rosapi/publishers": publishers,
        "/rosapi/subscribers": subscribers,
        "/rosapi/services": services,
        "/rosapi/service_type": service_type,
        "/rosapi/services_for_type": services_for_type,
        "/rosapi/get_time": get_time,
    }
