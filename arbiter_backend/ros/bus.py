"""The topic bus of the rosbridge endpoint in ROS mode: every topic is a real DDS topic.

Same interface as ``bus.TopicBus`` (declare, type_of, topics, subscribe,
publish, plus advertise/unadvertise), so ``bridge.RosbridgeEndpoint`` relays
WebSocket <-> DDS unchanged. One publisher per advertised topic and one
subscription per subscribed topic are shared by all clients. Subscription
callbacks run on the executor's thread; each message is taken serialized (CDR),
deserialized there, and handed to the asyncio loop with ``call_soon_threadsafe``,
where the endpoint's callbacks run, as they do on the embedded bus (its JSON form
is made on first use, see ``RosMessage``).

The relay's reader also measures its topic for the topic monitor (``tap``,
``relayed``): a second reader of a camera in this process made DDS deliver the
small topics beside it up to 0.46 s late (docs/BENCHMARKS.md, session 16).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rclpy.duration import Duration
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from rclpy.subscription import Subscription

from arbiter_core.msgtypes import MessageError, normalize_type
from arbiter_core.topics import QOS_DEPTH, is_command

from ..bus import Callback, TypeClash

if TYPE_CHECKING:
    from ..bus import Bus, ConvertingBus, GraphBus
from .convert import message_class, to_cbor, to_json, to_ros
from .graph import RosGraph
from .local import HandledLocally

log = logging.getLogger(__name__)
SWAP_MEMORY = 256  # messages of a replaced subscription remembered while its successor catches up
EARLY_LIFESPAN_S = 1.0  # what a non-command publisher of a client keeps for readers still matching
REMATCH_S = 1.0  # how often the publishers of relayed topics are looked at: a driver that starts late is
# matched within a second of being discovered, for one graph query per subscribed topic a second


@dataclass
class _Pub:
    type_name: str
    publisher: Publisher[Any]
    users: int = 0


@dataclass
class _Sub:
    type_name: str
    subscription: Subscription[Any]
    qos: QoSProfile
    callbacks: list[Callback] = field(default_factory=list)
    generation: int = 0  # bumped when the DDS subscription is replaced (publishers' QoS changed)
    retiring: Subscription[Any] | None = None  # the one replaced, kept until the new one delivers
    swap: _Swap | None = None  # while both deliver: which of their messages are handed on
    # a transient-local (latched) topic: its last ``depth`` samples, replayed to each client that
    # subscribes after the shared DDS subscription got them (as a late-joining DDS reader would get them)
    latched: deque[tuple[float, dict[str, Any]]] | None = None  # (monotonic time received, message)
    lifespan: float | None = None  # the shortest of the publishers' lifespans: older samples are not replayed


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
        key = json.dumps(json_form(data), sort_keys=True, default=str)
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


def publisher_qos(topic: str, type_name: str, latch: bool) -> QoSProfile:
    """The QoS of a publisher a WebSocket client made (``advertise``, or a ``publish`` without one).

    - ``latch``: transient-local, its last ``depth`` samples kept for every late reader, as long as it
      lives (rosbridge's latched publisher).
    - a velocity command (``topics.is_command``: stamped_cmd_vel, cmd_vel_measured, cmd_vel, Twist,
      TwistStamped): volatile, so that no reader, however late it matches, ever gets a command
      published before it matched; a robot acts on commands as they come, never on old ones.
    - anything else: transient-local with a lifespan of ``EARLY_LIFESPAN_S``, as the stock rosbridge
      server makes them: a transient-local reader still matching while a client publishes (discovery
      takes up to a few seconds on a loaded machine) gets what was published in the last second, and
      never anything older. A volatile reader gets only what follows its match, as DDS defines."""
    qos = default_qos()
    if latch:
        qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
    elif not is_command(topic, type_name):
        qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
        qos.lifespan = Duration(nanoseconds=int(EARLY_LIFESPAN_S * 1e9))
    return qos


def lifespan_s(profile: QoSProfile) -> float | None:
    """A profile's lifespan in seconds; None when samples never expire (rmw reports that as 0 or the
    largest duration)."""
    ns = profile.lifespan.nanoseconds
    return ns / 1e9 if 0 < ns < 2**63 - 1 else None


class RosMessage(dict[str, Any]):
    """A message as the endpoint gets it: rosbridge's JSON form, with the ROS message it came from
    and when it was received (wall clock, ns), for the CBOR encodings.

    The JSON form is made on first use, on the asyncio loop: a camera's subscribers that all ask for
    CBOR never need it, and it costs 4.3 ms of the executor's thread per 1280x720 frame (base64 of
    2.7 MB; ``to_cbor`` takes 0.4 ms). Python-level reads fill it first (the methods below; overriding
    ``__iter__`` keeps ``dict(m)`` and ``{**m}`` off CPython's fast path, which would read the storage
    unfilled). ``json.dumps`` reads a dict's storage directly, subclass or not: what serialises one
    calls ``filled()`` first (the endpoint through ``RosBus.json_form``)."""

    __slots__ = ("_filled", "raw", "received_ns", "ros")

    def __init__(self, ros: Any, received_ns: int, raw: bytes | None = None) -> None:
        super().__init__()
        self.ros = ros
        self.received_ns = received_ns
        self.raw = raw  # its CDR bytes as DDS delivered them (``cbor-raw`` sends them as they are)
        self._filled = False

    def _fill(self) -> None:
        if not self._filled:
            self._filled = True
            dict.update(self, to_json(self.ros))

    def filled(self) -> RosMessage:
        """This message with its JSON form made (once)."""
        self._fill()
        return self

    def __getitem__(self, key: Any) -> Any:
        self._fill()
        return dict.__getitem__(self, key)

    def __iter__(self) -> Any:
        self._fill()
        return dict.__iter__(self)

    def __len__(self) -> int:
        self._fill()
        return dict.__len__(self)

    def __contains__(self, key: object) -> bool:
        self._fill()
        return dict.__contains__(self, key)

    def __eq__(self, other: object) -> bool:
        self._fill()
        if isinstance(other, RosMessage):
            other._fill()
        return dict.__eq__(self, other)

    def __repr__(self) -> str:
        self._fill()
        return dict.__repr__(self)

    def get(self, key: Any, default: Any = None) -> Any:
        self._fill()
        return dict.get(self, key, default)

    def keys(self) -> Any:
        self._fill()
        return dict.keys(self)

    def items(self) -> Any:
        self._fill()
        return dict.items(self)

    def values(self) -> Any:
        self._fill()
        return dict.values(self)

    def copy(self) -> dict[str, Any]:
        self._fill()
        return dict(dict.items(self))


def json_form(msg: dict[str, Any]) -> dict[str, Any]:
    """rosbridge's JSON form of a message the bus delivered, ready for ``json.dumps``."""
    return msg.filled() if isinstance(msg, RosMessage) else msg


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
        self.interfaces: Any = None  # RosInterfaces: services and actions across the bridge (backend.py)
        # the topic monitor's share of the relay's readers (see ``relayed``): each message the relay takes
        # on a volatile reader, as (topic, CDR bytes, receive time in ns); executor thread
        self.tap: Callable[[str, bytes, int], None] | None = None
        self._undecodable: set[str] = set()  # topics whose bytes did not fit their type (told once)
        # the rest of the graph, for rosapi and call_service (rosapi.Graph)
        self.graph = RosGraph(node, loop, self.topics)

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
            pub = _Pub(t, self.node.create_publisher(message_class(t), topic, publisher_qos(topic, t, latch)))
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
            pub = _Pub(t, self.node.create_publisher(message_class(t), topic, publisher_qos(topic, t, False)))
            self._pubs[topic] = pub
        pub.publisher.publish(ros_msg)
        self.published += 1
        return msg if isinstance(msg, dict) else {}

    # -- subscribing ---------------------------------------------------------------------------
    def _qos_for(self, topic: str) -> tuple[QoSProfile, float | None]:
        """The QoS that matches every publisher there is, as rosbridge chooses it: best effort if any
        publisher is (a best-effort reader matches reliable writers too, a reliable one no best-effort
        writer); transient-local only if every publisher is (a transient-local reader matches no volatile
        writer). No publisher yet: reliable and volatile. With it, the shortest lifespan of the
        publishers (None: their samples never expire), which the relay's replay honours."""
        qos = default_qos()
        try:
            infos = self.node.get_publishers_info_by_topic(topic)
        except Exception:  # the graph query is best effort; the default works for most topics
            return qos, None
        infos = [i for i in infos if i.node_name != self.node.get_name()]  # not our own relay publisher
        if not infos:
            return qos, None
        profiles = [i.qos_profile for i in infos]
        if any(p.reliability == ReliabilityPolicy.BEST_EFFORT for p in profiles):
            qos.reliability = ReliabilityPolicy.BEST_EFFORT
        if all(p.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in profiles):
            qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
        spans = [s for s in map(lifespan_s, profiles) if s is not None]
        return qos, min(spans) if spans else None

    def _create_subscription(
        self, topic: str, type_name: str, qos: QoSProfile, generation: int
    ) -> Subscription[Any]:
        log.debug("%s: subscribing (%s, %s)", topic, qos.reliability.name, qos.durability.name)
        events = SubscriptionEventCallbacks(
            matched=lambda info: log.debug(
                "%s: reader matched %d writers (%+d)", topic, info.current_count, info.current_count_change
            ),
            incompatible_qos=lambda info: self._on_incompatible(topic, info),
        )
        cls = message_class(type_name)
        return self.node.create_subscription(
            cls,
            topic,
            lambda raw, info: self._on_message(topic, cls, raw, info, generation),
            qos,
            event_callbacks=events,
            raw=True,  # the CDR bytes: their size for the topic monitor (``tap``), as is for cbor-raw
        )

    def _on_incompatible(self, topic: str, info: Any) -> None:  # executor thread
        """A publisher our reader cannot match appeared: follow it now, not at the next poll."""
        kind = info.last_policy_kind
        log.info("%s: a publisher's QoS does not match the relay's (%s); re-matching", topic, kind)
        with contextlib.suppress(RuntimeError):  # the loop is closed: shutting down
            self.loop.call_soon_threadsafe(self.rematch)

    def rematch(self) -> None:  # asyncio loop
        """Follow the publishers: where the QoS that matches them all changed (a best-effort driver
        started after the client subscribed, a publisher restarted with other settings), replace the
        DDS subscription. The new one is made first; the old one keeps delivering until the new one
        delivers its first message, and is then dropped, so the swap loses nothing the middleware
        delivers and a message is not handed on twice (see ``_on_message``)."""
        for topic, sub in list(self._subs.items()):
            want, sub.lifespan = self._qos_for(topic)
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

    async def watch_publishers(
        self, period: float = REMATCH_S, beat: Callable[[str], None] | None = None
    ) -> None:
        """Call :meth:`rematch` every ``period`` seconds until cancelled; an error ends it (the backend's
        supervisor logs it once and calls this again: ``supervise.py``). ``beat``: the supervisor's, each
        round, as worker ``qos-follower``."""
        while True:
            await asyncio.sleep(period)
            if beat is not None:
                beat("qos-follower")
            self.rematch()

    def subscribe(self, topic: str, callback: Callback, type_name: str | None = None) -> Callable[[], None]:
        t = self.declare(topic, type_name) if type_name is not None else self.type_of(topic)
        if t is None:
            raise MessageError(f"cannot subscribe to {topic}: type unknown")
        sub = self._subs.get(topic)
        if sub is None:
            qos, lifespan = self._qos_for(topic)
            latched: deque[tuple[float, dict[str, Any]]] | None = (
                deque(maxlen=qos.depth) if qos.durability == DurabilityPolicy.TRANSIENT_LOCAL else None
            )
            created = self._create_subscription(topic, t, qos, 0)
            sub = _Sub(t, created, qos, latched=latched, lifespan=lifespan)
            self._subs[topic] = sub
        elif sub.latched:
            # DDS delivered the latched samples once, to the shared subscription: this client gets them
            # from the relay, and only this client; not those past their publisher's lifespan
            now = time.monotonic()
            kept = tuple(d for at, d in sub.latched if sub.lifespan is None or now - at <= sub.lifespan)
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

    def _ros_of(self, type_name: str | None, msg: dict[str, Any]) -> Any:
        ros = getattr(msg, "ros", None)
        if ros is not None:
            return ros
        if type_name is None:
            raise MessageError("message type unknown")
        return to_ros(message_class(type_name), msg)  # one handed over in-process (deliver_local)

    def json_form(self, msg: dict[str, Any]) -> dict[str, Any]:
        """The endpoint serialises through this (``bridge.encoding``): module ``json_form``."""
        return json_form(msg)

    def cbor_values(self, type_name: str | None, msg: dict[str, Any]) -> dict[str, Any]:
        """rosbridge's CBOR form of a message this bus delivered (typed arrays, byte strings)."""
        return to_cbor(self._ros_of(type_name, msg))

    def cdr(self, type_name: str | None, msg: dict[str, Any]) -> tuple[bytes, int]:
        """The CDR serialisation of a message this bus delivered (``cbor-raw``) and when it came (ns)."""
        raw = getattr(msg, "raw", None)
        if raw is None:  # one handed over in-process (deliver_local)
            raw = serialize_message(self._ros_of(type_name, msg))
        return raw, getattr(msg, "received_ns", time.time_ns())

    def relayed(self) -> dict[str, tuple[str, bool]]:
        """The topics the relay reads with a volatile reader, as (type, best effort): the topic monitor
        measures these through ``tap`` instead of a reader of its own. Any thread (a copy, made in
        one step under the GIL)."""
        subs = dict(self._subs)
        return {
            topic: (sub.type_name, sub.qos.reliability == ReliabilityPolicy.BEST_EFFORT)
            for topic, sub in subs.items()
            if sub.latched is None
        }

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

    def _on_message(
        self, topic: str, cls: type, raw: bytes, info: dict[str, Any], generation: int = 0
    ) -> None:  # executor thread
        sub = self._subs.get(topic)
        if sub is None:
            return
        received_ns = info.get("received_timestamp") or time.time_ns()  # the middleware's, wall clock
        try:
            msg: Any = deserialize_message(raw, cls)
        except Exception:  # bytes that do not fit the type (a foreign publisher): skipped, never fatal
            if topic not in self._undecodable:
                self._undecodable.add(topic)
                log.warning("%s: a message that does not deserialise as %s (skipped)", topic, cls.__name__)
            if generation == sub.generation:
                self._measure(sub, topic, raw, received_ns)  # it still arrived: the monitor counts it
            return
        data = RosMessage(msg, received_ns, raw)  # its JSON form is made where it is first needed
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
        self._measure(sub, topic, raw, received_ns)
        text = getattr(msg, "data", None)
        handled = self._local.get(topic)
        if handled is not None and isinstance(text, str) and handled.take(text):
            return  # already delivered in-process
        with contextlib.suppress(RuntimeError):  # the loop is closed: shutting down
            self.loop.call_soon_threadsafe(self._fanout, topic, data)

    def _measure(self, sub: _Sub, topic: str, raw: bytes, received_ns: int) -> None:  # executor thread
        """Hand a message the relay took to the topic monitor (``tap``); not from a transient-local
        reader, whose history replayed on subscribing is no arrival."""
        if self.tap is not None and sub.latched is None:
            self.tap(topic, raw, received_ns)

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
            sub.latched.append((time.monotonic(), data))
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
        self.graph.close()
        self._subs.clear()
        self._pubs.clear()


if TYPE_CHECKING:

    def _capabilities(bus: RosBus) -> tuple[Bus, GraphBus, ConvertingBus]:
        """What the endpoint finds by isinstance, stated for the type check: a rename on either side
        fails it (the embedded TopicBus is neither a GraphBus nor a ConvertingBus)."""
        return bus, bus, bus
