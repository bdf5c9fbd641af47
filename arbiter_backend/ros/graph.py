"""The ROS graph beyond the relayed topics, as rosapi and ``call_service`` see it (``rosapi.Graph``):
the nodes, who publishes, subscribes and serves what, the service types, and calls to any service."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from typing import Any

from rclpy.node import Node

from arbiter_core.msgtypes import MessageError

from .convert import service_class, to_json, to_ros, typedef_text
from .futures import on_loop


def _full(name: str, namespace: str) -> str:
    """``/ns/name`` (``/name`` in the root namespace), as rosapi names nodes."""
    return f"{namespace.rstrip('/')}/{name}"


class RosGraph:
    def __init__(
        self, node: Node, loop: asyncio.AbstractEventLoop, topics: Callable[[], list[tuple[str, str]]]
    ) -> None:
        self.node = node
        self.loop = loop
        self.topics = topics  # the relay's: the graph's topics and those declared through it
        self._clients: dict[str, tuple[type, Any]] = {}  # service -> (its type's class, the rclpy client)

    def node_names(self) -> list[str]:
        return [_full(name, ns) for name, ns in self.node.get_node_names_and_namespaces()]

    def topic_endpoints(self, topic: str) -> tuple[list[str], list[str]]:
        pubs = [_full(i.node_name, i.node_namespace) for i in self.node.get_publishers_info_by_topic(topic)]
        subs = [
            _full(i.node_name, i.node_namespace) for i in self.node.get_subscriptions_info_by_topic(topic)
        ]
        return pubs, subs

    def node_endpoints(self, node: str) -> tuple[list[str], list[str], list[str]]:
        ns, _, name = node.rpartition("/")
        ns = ns or "/"
        return (
            [t for t, _ in self.node.get_subscriber_names_and_types_by_node(name, ns)],
            [t for t, _ in self.node.get_publisher_names_and_types_by_node(name, ns)],
            [s for s, _ in self.node.get_service_names_and_types_by_node(name, ns)],
        )

    def service_names_and_types(self) -> list[tuple[str, list[str]]]:
        return [(name, list(types)) for name, types in self.node.get_service_names_and_types()]

    @staticmethod
    def typedef_text(type_name: str) -> str:
        return typedef_text(type_name)

    async def call_service(self, service: str, args: Any) -> dict[str, Any]:  # asyncio loop
        """Call ``service`` (any on the graph; its type from the graph) with rosbridge ``args`` (an object
        keyed by field, or a list in field order; anything else: the default request); the response in
        JSON form. MessageError when there is no such service or the args do not fit. The caller
        bounds the wait; a cancelled call is withdrawn from the client."""
        types = dict(self.node.get_service_names_and_types()).get(service)
        if not types:
            raise MessageError(f"Service {service} does not exist")
        srv = service_class(types[0])
        if isinstance(args, list):
            args = dict(zip(srv.Request.get_fields_and_field_types(), args, strict=False))
        request = to_ros(srv.Request, args if isinstance(args, dict) else {}, path="args")
        cached = self._clients.get(service)
        if cached is None or cached[0] is not srv:
            if cached is not None:
                self.node.destroy_client(cached[1])
            cached = self._clients[service] = (srv, self.node.create_client(srv, service))
        client = cached[1]
        for _ in range(20):  # up to 1 s for the server side to be matched, as rosbridge waits
            if client.service_is_ready():
                break
            await asyncio.sleep(0.05)
        else:
            raise MessageError(f"Service {service} is not available")
        future = client.call_async(request)
        answer = on_loop(self.loop, future)
        try:
            response = await answer
        except asyncio.CancelledError:
            with contextlib.suppress(Exception):
                client.remove_pending_request(future)
            raise
        return to_json(response)

    def close(self) -> None:
        for _, client in self._clients.values():
            self.node.destroy_client(client)
        self._clients.clear()
