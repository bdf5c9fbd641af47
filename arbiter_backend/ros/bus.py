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
import json
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
SWAP_MEMORY = 256  # messages of a replaced subscription remembered while its successor catches up
REMATCH_S = 1.0  # how often the publishers of relayed topics are looked at: a driver that starts late is
# matched within a second of being discovered, for one graph query per subscribed topic a second


@dataclass
class _Pub:
    type_name: str
    publisher: Publisher
    users: int = 0


@dataclass
class _Sub:
    type_name: str
    subscription: Subscription
    qos: QoSProfile
    callbacks: list[Callback] = field(default_factory=list)
    generation: int = 0  # bumped when the DDS subscription is replaced (publishers' QoS changed)
    retiring: Subscription | None = None  # the one replaced, kept until the new one delivers
    swap: _Swap | None = None  # while both deliver: which of their messages are handed on
    # a transient-local (latched) topic: its last ``depth`` samples, replayed to each client that
    # subscribes after the shared DDS subscription got them (as a late-joining DDS reader would get them)
    latched: deque[dict[str, Any]] | None = None


class _Swap:
    """The overlap of a replaced DDS subscription and its successor (executor thread only).

    The old one's messages are handed on until the new one delivers; from then on only the new one's,
    except a message the old one already handed on (both were matched to its publisher): the texts the
    old one handed on are kept, and the new one's copy of each is skipped once."""

    def __init__(self, old_generation: int) -> None:
        self.old = old_generation
        self.new_started = False
        self.fresh = False
        self.seen: deque[str] = deque(maxlen=SWAP_MEMORY)

    def admit(self, generation: int, data: dict[str, Any]) -> bool:
        if generation < self.old:
            return False
        key = json.dumps(data, sort_keys=True, default=str)
        if generation == self.old:
            if self.new_started:
                return False  # the new one delivers now
            self.seen.append(key)
            return True
        self.new_started = True
        if key in self.seen:
            self.seen.remove(key)
            return False
        self.fresh = True  # past what the old one handed on (a publisher's messages keep their order)
        return True

    @property
    def over(self) -> bool:
        """The new one delivers, and nothing the old one handed on is still to come from it."""
        return self.new_started and (self.fresh or not self.seen)


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
    def advertise(self, topic: str, type_name: str, latch: bool = False) -> str:
        """Create (or share) the DDS publisher now, so subscribers match before the first message;
        ``latch`` (rosbridge's field) makes it transient-local: a late reader gets its last samples."""
        t = self.declare(topic, type_name)
        pub = self._pubs.get(topic)
        if pub is None:
            qos = default_qos()
            if latch:
                qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
            pub = _Pub(t, self.node.create_publisher(message_class(t), topic, qos))
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
        """The QoS that matches every publisher there is, as rosbridge chooses it: best effort if any
        publisher is (a best-effort reader matches reliable writers too, a reliable one no best-effort
        writer); transient-local only if every publisher is (a transient-local reader matches no volatile
        writer). No publisher yet: reliable and volatile."""
        qos = default_qos()
        try:
            infos = self.node.get_publishers_info_by_topic(topic)
        except Exception:  # the graph query is best effort; the default works for most topics
            return qos
        infos = [i for i in infos if i.node_name != self.node.get_name()]  # not our own relay publisher
        if infos:
            profiles = [i.qos_profile for i in infos]
            if any(p.reliability == ReliabilityPolicy.BEST_EFFORT for p in profiles):
                qos.reliability = ReliabilityPolicy.BEST_EFFORT
            if all(p.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in profiles):
                qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
        return qos

    def _create_subscription(
        self, topic: str, type_name: str, qos: QoSProfile, generation: int
    ) -> Subscription:
        return self.node.create_subscription(
            message_class(type_name), topic, lambda m: self._on_message(topic, m, generation), qos
        )

    def rematch(self) -> None:  # asyncio loop
        """Follow the publishers: where the QoS that matches them all changed (a best-effort driver
        started after the client subscribed, a publisher restarted with other settings), replace the
        DDS subscription. The new one is made first; the old one keeps delivering until the new one
        delivers its first message, and is then dropped, so the swap loses nothing the middleware
        delivers and a message is not handed on twice (see ``_on_message``)."""
        for topic, sub in list(self._subs.items()):
            want = self._qos_for(topic)
            if (want.reliability, want.durability) == (sub.qos.reliability, sub.qos.durability):
                continue
            log.info(
                "%s: its publishers changed; subscribing %s, %s", topic, want.reliability, want.durability
            )
            if sub.retiring is not None:  # replaced twice before the first new message: drop the oldest
                self.node.destroy_subscription(sub.retiring)
            sub.swap = _Swap(sub.generation)
            sub.generation += 1
            sub.retiring = sub.subscription
            sub.subscription = self._create_subscription(topic, sub.type_name, want, sub.generation)
            sub.qos = want
            latched = want.durability == DurabilityPolicy.TRANSIENT_LOCAL
            sub.latched = (sub.latched or deque(maxlen=want.depth)) if latched else None

    async def watch_publishers(self, period: float = REMATCH_S) -> None:
        """Call :meth:`rematch` every ``period`` seconds until cancelled."""
        while True:
            await asyncio.sleep(period)
            try:
                self.rematch()
            except Exception:  # never let the graph take the relay down
                log.exception("following the publishers failed")

    def subscribe(self, topic: str, callback: Callback, type_name: str | None = None) -> Callable[[], None]:
        t = self.declare(topic, type_name) if type_name is not None else self.type_of(topic)
        if t is None:
            raise MessageError(f"cannot subscribe to {topic}: type unknown")
        sub = self._subs.get(topic)
        if sub is None:
            qos = self._qos_for(topic)
            latched = deque(maxlen=qos.depth) if qos.durability == DurabilityPolicy.TRANSIENT_LOCAL else None
            sub = _Sub(t, self._create_subscription(topic, t, qos, 0), qos, latched=latched)
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
                if current.retiring is not None:
                    self.node.destroy_subscription(current.retiring)

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

    def _on_message(self, topic: str, msg: Any, generation: int = 0) -> None:  # executor thread
        sub = self._subs.get(topic)
        if sub is None:
            return
        try:
            data = to_json(msg)
        except Exception:
            log.exception("cannot convert a message on %s", topic)
            return
        swap = sub.swap
        if swap is not None:
            if not swap.admit(generation, data):
                return
            if swap.new_started and sub.retiring is not None:  # the new one delivers: drop the old one
                retired, sub.retiring = sub.retiring, None
                with contextlib.suppress(RuntimeError):
                    self.loop.call_soon_threadsafe(self.node.destroy_subscription, retired)
            if swap.over:
                sub.swap = None
        elif generation != sub.generation:
            return  # a replaced subscription's last messages, after the swap ended
        text = getattr(msg, "data", None)
        handled = self._local.get(topic)
        if handled is not None and isinstance(text, str) and handled.take(text):
            return  # already delivered in-process
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
            if sub.retiring is not None:
                self.node.destroy_subscription(sub.retiring)
        for pub in self._pubs.values():
            self.node.destroy_publisher(pub.publisher)
        self._subs.clear()
        self._pubs.clear()
