"""The topic bus of the rosbridge endpoint in ROS mode: every topic is a real DDS topic.

Same interface as ``bus.TopicBus`` (declare, type_of, topics, subscribe,
publish, plus advertise/unadvertise), so ``bridge.RosbridgeEndpoint`` relays
WebSocket <-> DDS unchanged. One publisher per advertised topic and one
subscription per subscribed topic are shared by all clients. Subscription
callbacks run on the executor's thread; each message is converted to JSON
there, once, and handed to the asyncio loop with ``call_soon_threadsafe``, where
the endpoint's callbacks run, as they do on the embedded bus.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.subscription import Subscription

from arbiter_core.msgtypes import MessageError, normalize_type
from arbiter_core.topics import QOS_DEPTH

from ..bus import Callback, TypeClash
from .convert import message_class, to_json, to_ros
from .local import HandledLocally

log = logging.getLogger(__name__)


@dataclass
class _Pub:
    type_name: str
    publisher: Publisher
    users: int = 0


@dataclass
class _Sub:
    type_name: str
    subscription: Subscription
    callbacks: list[Callback] = field(default_factory=list)
    # a transient-local (latched) topic: its last ``depth`` samples, replayed to each client that
    # subscribes after the shared DDS subscription got them (as a late-joining DDS reader would get them)
    latched: deque[dict[str, Any]] | None = None


def default_qos() -> QoSProfile:
    return QoSProfile(
        depth=QOS_DEPTH, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE
    )


class RosBus:
    def __init__(self, node: Node, loop: asyncio.AbstractEventLoop) -> None:
        self.node = node
        self.loop = loop
        self._declared: dict[str, str] = {}
        self._pubs: dict[str, _Pub] = {}
        self._subs: dict[str, _Sub] = {}
        self.published = 0
        # texts handed over in-process (deliver_local), so that their DDS copy is not fanned out twice
        self._local: dict[str, HandledLocally] = {}
        self.local_delivered = 0
        self.local_handlers: dict[str, Callable[[str], None]] = {}  # topic -> a node's in-process handler

    # -- types ------------------------------------------------------------------------------
    def _graph(self) -> dict[str, list[str]]:
        return {name: list(types) for name, types in self.node.get_topic_names_and_types()}

    def declare(self, topic: str, type_name: str) -> str:
        t = normalize_type(type_name)
        message_class(t)  # MessageError if the type is not installed here
        have = self._declared.get(topic)
        if have is None:
            graph_types = self._graph().get(topic, [])
            if graph_types and t not in graph_types:
                have = graph_types[0]
        if have is not None and have != t:
            raise TypeClash(f"topic {topic} has type {have}, not {t}")
        self._declared[topic] = t
        return t

    def type_of(self, topic: str) -> str | None:
        have = self._declared.get(topic)
        if have is not None:
            return have
        types = self._graph().get(topic)
        return types[0] if types else None

    def topics(self) -> list[tuple[str, str]]:
        merged = {name: types[0] for name, types in self._graph().items() if types}
        merged.update(self._declared)
        return sorted(merged.items())

    # -- publishing ---------------------------------------------------------------------------
    def advertise(self, topic: str, type_name: str) -> str:
        """Create (or share) the DDS publisher now, so subscribers match before the first message."""
        t = self.declare(topic, type_name)
        pub = self._pubs.get(topic)
        if pub is None:
            pub = _Pub(t, self.node.create_publisher(message_class(t), topic, default_qos()))
            self._pubs[topic] = pub
        pub.users += 1
        return t

    def unadvertise(self, topic: str) -> None:
        pub = self._pubs.get(topic)
        if pub is None:
            return
        pub.users -= 1
        if pub.users <= 0:
            del self._pubs[topic]
            self.node.destroy_publisher(pub.publisher)

    def publish(self, topic: str, msg: Any, type_name: str | None = None) -> dict[str, Any]:
        t = self.declare(topic, type_name) if type_name is not None else self.type_of(topic)
        if t is None:
            raise MessageError(f"cannot infer the type of {topic}: not yet advertised")
        ros_msg = to_ros(message_class(t), msg)
        handler = self.local_handlers.get(topic)
        if handler is not None and isinstance(getattr(ros_msg, "data", None), str):
            handler(ros_msg.data)  # in-process first: it registers the text before the DDS copy exists
        pub = self._pubs.get(topic)
        if pub is None:  # published without advertise: keep a publisher, as rosbridge does
            pub = _Pub(t, self.node.create_publisher(message_class(t), topic, default_qos()))
            self._pubs[topic] = pub
        pub.publisher.publish(ros_msg)
        self.published += 1
        return msg if isinstance(msg, dict) else {}

    # -- subscribing ---------------------------------------------------------------------------
    def _qos_for(self, topic: str) -> QoSProfile:
        """Match the publishers, as rosbridge does: best effort if they all are; latched if they all are."""
        qos = default_qos()
        try:
            infos = self.node.get_publishers_info_by_topic(topic)
        except Exception:  # the graph query is best effort; the default works for most topics
            return qos
        if infos:
            profiles = [i.qos_profile for i in infos]
            if all(p.reliability == ReliabilityPolicy.BEST_EFFORT for p in profiles):
                qos.reliability = ReliabilityPolicy.BEST_EFFORT
            if all(p.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in profiles):
                qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
        return qos

    def subscribe(self, topic: str, callback: Callback, type_name: str | None = None) -> Callable[[], None]:
        t = self.declare(topic, type_name) if type_name is not None else self.type_of(topic)
        if t is None:
            raise MessageError(f"cannot subscribe to {topic}: type unknown")
        sub = self._subs.get(topic)
        if sub is None:
            cls = message_class(t)
            qos = self._qos_for(topic)
            ros_sub = self.node.create_subscription(
                cls, topic, lambda m, name=topic: self._on_message(name, m), qos
            )
            latched = deque(maxlen=qos.depth) if qos.durability == DurabilityPolicy.TRANSIENT_LOCAL else None
            sub = _Sub(t, ros_sub, latched=latched)
            self._subs[topic] = sub
        elif sub.latched:
            # DDS delivered the latched samples once, to the shared subscription: this client gets them
            # from the relay, and only this client
            kept = tuple(sub.latched)
            self.loop.call_soon(self._replay, topic, callback, kept)
        sub.callbacks.append(callback)

        def unsubscribe() -> None:
            current = self._subs.get(topic)
            if current is None or callback not in current.callbacks:
                return
            current.callbacks.remove(callback)
            if not current.callbacks:
                del self._subs[topic]
                self.node.destroy_subscription(current.subscription)

        return unsubscribe

    def subscriber_count(self, topic: str) -> int:
        sub = self._subs.get(topic)
        return len(sub.callbacks) if sub else 0

    def deliver_local(self, topic: str, text: str) -> None:
        """A ``std_msgs/String`` published by a node of this process (the tracker's report), handed to
        the WebSocket subscribers at once instead of after a DDS round through the executor; it is
        still published on DDS for everyone else, and that copy is not fanned out again here."""
        handled = self._local.get(topic)
        if handled is None:
            handled = self._local.setdefault(topic, HandledLocally())
        handled.note(text)
        self.local_delivered += 1
        with contextlib.suppress(RuntimeError):  # the loop is closed: shutting down
            self.loop.call_soon_threadsafe(self._fanout, topic, {"data": text})

    def _on_message(self, topic: str, msg: Any) -> None:  # executor thread
        text = getattr(msg, "data", None)
        handled = self._local.get(topic)
        if handled is not None and isinstance(text, str) and handled.take(text):
            return  # already delivered in-process
        try:
            data = to_json(msg)
        except Exception:
            log.exception("cannot convert a message on %s", topic)
            return
        with contextlib.suppress(RuntimeError):  # the loop is closed: shutting down
            self.loop.call_soon_threadsafe(self._fanout, topic, data)

    def _replay(self, topic: str, callback: Callback, kept: tuple[dict[str, Any], ...]) -> None:  # loop
        current = self._subs.get(topic)
        if current is None or callback not in current.callbacks:
            return  # unsubscribed meanwhile
        for data in kept:
            try:
                callback(data)
            except Exception:
                log.exception("subscriber of %s failed", topic)

    def _fanout(self, topic: str, data: dict[str, Any]) -> None:  # asyncio loop
        sub = self._subs.get(topic)
        if sub is None:
            return
        if sub.latched is not None:
            sub.latched.append(data)
        for cb in tuple(sub.callbacks):
            try:
                cb(data)
            except Exception:
                log.exception("subscriber of %s failed", topic)

    def close(self) -> None:
        for sub in self._subs.values():
            self.node.destroy_subscription(sub.subscription)
        for pub in self._pubs.values():
            self.node.destroy_publisher(pub.publisher)
        self._subs.clear()
        self._pubs.clear()
