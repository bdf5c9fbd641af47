"""The ROS graph beyond the relayed topics, as rosapi and ``call_service`` see it (``rosapi.Graph``):
the nodes, who publishes, subscribes and serves what, the service types, and calls to any service."""

from __future__ import annotations

import asyncio
import contextlib
import functools
from collections.abc import Callable
from importlib import metadata
from typing import Any

from rclpy.node import Node, NodeNameNonExistentError

from arbiter_core.msgtypes import MessageError

from . import typedefs
from .convert import service_class, to_json, to_ros, typedef_text
from .futures import on_loop

# rclpy's major version -> its ROS 2 distribution (get_ros_version where ROS_DISTRO is not set, as with
# the PyPI wheels, which set no environment)
RCLPY_DISTROS = {3: "humble", 4: "iron", 7: "jazzy", 9: "kilted", 10: "rolling"}


@functools.lru_cache(maxsize=1)
def rclpy_distro() -> str:
    """The distribution of the installed rclpy, by its version; "" when it cannot be told."""
    for dist in ("rclpy", "ros-rclpy"):
        try:
            return RCLPY_DISTROS.get(int(metadata.version(dist).split(".")[0]), "")
        except (metadata.PackageNotFoundError, ValueError):
            continue
    return ""


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
        """The node's topics it subscribes and publishes, and its services; all empty when it left the
        graph since it was listed (rosapi's answer then, as the stock node's)."""
        ns, _, name = node.rpartition("/")
        ns = ns or "/"
        try:
            return (
                [t for t, _ in self.node.get_subscriber_names_and_types_by_node(name, ns)],
                [t for t, _ in self.node.get_publisher_names_and_types_by_node(name, ns)],
                [s for s, _ in self.node.get_service_names_and_types_by_node(name, ns)],
            )
        except NodeNameNonExistentError:
            return [], [], []

    def node_services(self, node: str) -> list[tuple[str, list[str]]]:
        ns, _, name = node.rpartition("/")
        try:
            found = self.node.get_service_names_and_types_by_node(name, ns or "/")
        except NodeNameNonExistentError:  # the node left since it was listed
            return []
        return [(service, list(types)) for service, types in found]

    def service_names_and_types(self) -> list[tuple[str, list[str]]]:
        return [(name, list(types)) for name, types in self.node.get_service_names_and_types()]

    def topic_names(self) -> list[str]:
        return [name for name, _types in self.node.get_topic_names_and_types()]

    @staticmethod
    def typedef_text(type_name: str) -> str:
        return typedef_text(type_name)

    @staticmethod
    def message_typedefs(type_name: str) -> list[dict[str, Any]]:
        return typedefs.message_typedefs(type_name)

    @staticmethod
    def service_typedefs(type_name: str, part: str) -> list[dict[str, Any]]:
        return typedefs.service_typedefs(type_name, part)

    @staticmethod
    def distro() -> str:
        return rclpy_distro()

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
