"""The topic monitor on DDS: every topic on the graph, measured from serialized messages.

One node (``arbiter_topic_monitor``), on a thread of its own and in no executor: every ``GRAPH_S``
seconds it looks at the graph and subscribes to each topic the filter wants, with ``raw=True`` (the
CDR bytes, never a deserialised message), volatile (no history to skew the rate), and reliable unless a
publisher is best effort (then best effort, which matches every publisher). Not best effort always, as
``ros2 topic hz`` subscribes: a best-effort reader loses a whole large message when one fragment is
lost (a 1 MB image at 15 Hz arrived at 5 Hz), and that loss would be measured as the topic's rate.
When the publishers' reliability changes, the subscription is made again.

Every ``TAKE_S`` the thread takes what each subscription holds, straight from its handle, and notes
each message's size and the middleware's receive time (so batching does not blur the periods); then it
lets the shared ``TopicWatch`` take its once-a-second rate samples (the history of the last minute). The
executor's per-message machinery (wait set rebuilt over every entity of the process, a task per
callback) is what made watching as dear as deserialising; it never sees these subscriptions. For a
type whose first field is a ``std_msgs/Header`` the stamp is read from the bytes right after the
4-byte encapsulation header (``int32 sec, uint32 nanosec``, in the byte order the encapsulation
names). A type not installed here cannot be subscribed (rclpy has no generic subscription): it is
listed with its type, counts and "type not installed here". A topic whose messages cannot be taken is
listed with the reason until its type or QoS change (its reader dropped, the others taken all the same).
A service's introspection topic
(``pkg/srv/Name_Event``) and an action's feedback (``pkg/action/Name_FeedbackMessage``) are message
types like any other (``arbiter_core.msgtypes.normalize_type``). A topic that cannot be looked at for
any other reason is listed with the reason ("cannot be read here: …"), and the others are followed all
the same. The loop runs under the backend's supervisor (``supervise.py``).

A topic the rosbridge relay reads with a volatile reader of the same reliability (a WebSocket client
subscribed to it) gets no reader of the monitor's own: the relay's messages are measured instead
(``relayed``, ``took``; the relay's reader takes the CDR bytes too, with the middleware's receive time).
Two readers of a 1280x720 camera in this process made DDS deliver a 20 Hz topic beside it up to 0.46 s
late, p95 27-218 ms, against 9-10 ms with one (docs/BENCHMARKS.md, session 16); one reader also
takes each message once instead of twice. The switch happens at the next look at the graph: when the
relay stops reading a topic, the monitor subscribes again within ``GRAPH_S``, and the topic's window
misses what came between (its rate, over the window, dips for that second).
"""

from __future__ import annotations

import contextlib
import logging
import struct
import threading
import time
from collections.abc import Callable
from typing import Any

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.subscription import Subscription

from arbiter_core.msgtypes import MessageError, normalize_type
from arbiter_core.topicstats import CANNOT_READ, NOT_INSTALLED, qos_mismatch

from ..supervise import Supervisor
from ..topicwatch import TopicWatch, follow
from .convert import message_class

log = logging.getLogger(__name__)

NODE_NAME = "arbiter_topic_monitor"
WORKER = "topic-monitor"  # its name among the backend's supervised workers
EXECUTOR_WORKER = "rclpy-executor"  # the relay's: the topics measured on its reader (``took``) stop with it
GRAPH_S = 1.0  # how often the graph is looked at: topics that appear are watched within a second
TAKE_S = 0.1  # how often the subscriptions are emptied: up to DEPTH / TAKE_S = 1 kHz per topic
DEPTH = 100

_STAMP_LE, _STAMP_BE = struct.Struct("<iI"), struct.Struct(">iI")


def cdr_stamp(raw: bytes) -> float | None:
    """``header.stamp`` of a serialized message whose first field is a Header, in seconds; None when the
    bytes cannot hold one (too short, nanoseconds out of range)."""
    if len(raw) < 12:
        return None
    sec: int
    nsec: int
    sec, nsec = (_STAMP_LE if raw[1] & 1 else _STAMP_BE).unpack_from(raw, 4)
    if nsec >= 1_000_000_000:
        return None
    return sec + nsec / 1e9


def has_header(cls: Any) -> bool:
    """The message's first field is a ``std_msgs/Header`` (as ``ros2 topic delay`` requires)."""
    fields = list(cls.get_fields_and_field_types().items())
    return bool(fields) and fields[0][1] == "std_msgs/Header"


def _node_names(infos: list[Any]) -> tuple[str, ...]:
    """``/namespace/node`` of each endpoint, sorted, each once."""
    names = {f"{i.node_namespace.rstrip('/')}/{i.node_name}" for i in infos}
    return tuple(sorted(names))


def _policy(profile: QoSProfile) -> tuple[str, str]:
    r = "best_effort" if profile.reliability == ReliabilityPolicy.BEST_EFFORT else "reliable"
    d = "transient_local" if profile.durability == DurabilityPolicy.TRANSIENT_LOCAL else "volatile"
    return r, d


class RosTopics:
    """Runs on its own thread (:meth:`start`): the node must not be added to an executor."""

    def __init__(self, node: Node, watch: TopicWatch, supervisor: Supervisor) -> None:
        self.node = node
        self.watch = watch
        self.supervisor = supervisor
        # topic -> (type, best effort, subscription, stamped)
        self._subs: dict[str, tuple[str, bool, Subscription[Any] | None, bool]] = {}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        # what the relay reads (``RosBus.relayed``): topic -> (type, best effort); set by the backend
        self.relayed: Callable[[], dict[str, tuple[str, bool]]] = dict
        self._shared: dict[str, bool] = {}  # topics measured on the relay's reader -> stamped
        self._unread: dict[str, str] = {}  # topics that could not be looked at -> why (``_unreadable``)

    def start(self) -> None:
        follow(self.supervisor, WORKER, self.watch, "monitor")
        # a topic measured on the relay's reader gets no message while its executor is down: unknown
        follow(self.supervisor, EXECUTOR_WORKER, self.watch, "executor")
        self._thread = self.supervisor.thread(WORKER, self._run, self._stop)

    def _run(self) -> None:
        """The monitor's loop, supervised (``supervise.py``): an error that ends it is logged once and the
        loop runs again, the topics' states ``unknown`` meanwhile (``topicwatch.follow``)."""
        next_look = 0.0
        while not self._stop.is_set():
            if time.monotonic() >= next_look:
                self.look()
                next_look = time.monotonic() + GRAPH_S
            try:
                self.take()
            except Exception:  # the node is being destroyed, or a handle went away: next sweep
                log.debug("taking messages failed", exc_info=True)
            self.watch.sample()  # the rate history: once a second per topic, whoever asks
            self.supervisor.beat(WORKER)  # after a round: its figures are whole again
            self._stop.wait(TAKE_S)

    def take(self) -> None:
        """Everything each subscription holds: size, receive time and, when stamped, the delay."""
        offset = time.monotonic() - time.time()  # middleware receive times are system time
        note = self.watch.note
        for topic, (type_name, best_effort, sub, stamped) in list(self._subs.items()):
            if sub is None:
                continue
            try:
                with sub.handle:
                    while (taken := sub.handle.take_message(sub.msg_type, True)) is not None:
                        raw, info = taken
                        self._note(note, topic, raw, info.get("received_timestamp", 0), stamped, offset)
            except Exception as exc:  # this topic only: listed with the reason, the others taken all the same
                self._subs[topic] = (type_name, best_effort, None, stamped)  # no reader: not retried
                with contextlib.suppress(Exception):
                    self.node.destroy_subscription(sub)
                self._unreadable(topic, type_name, exc)

    @staticmethod
    def _note(
        note: Callable[..., None], topic: str, raw: bytes, received_ns: int, stamped: bool, offset: float
    ) -> None:
        """One message: its size, when it came (``received_ns``: the middleware's wall clock, 0 when
        unknown; ``offset``: monotonic minus wall clock) and, when stamped, its delay."""
        received = received_ns / 1e9 or time.time()
        if not stamped:
            note(topic, len(raw), at=received + offset)
            return
        stamp = cdr_stamp(raw)
        if stamp is None:
            note(topic, len(raw), None, True, at=received + offset)
        else:
            note(topic, len(raw), received - stamp, at=received + offset)

    def took(self, topic: str, raw: bytes, received_ns: int) -> None:  # executor thread
        """The relay took a message of ``topic`` (``RosBus.tap``): measured if the monitor shares its
        reader, ignored while the monitor still has a reader of its own (no message counted twice)."""
        stamped = self._shared.get(topic)
        if stamped is not None:
            self._note(self.watch.note, topic, raw, received_ns, stamped, time.monotonic() - time.time())

    def answer(self) -> dict[str, Any]:
        return self.watch.answer()

    def look(self) -> None:  # the monitor's thread
        """Follow the graph: watch topics that appeared, drop those gone, refresh counts and QoS notes.
        A topic that cannot be looked at (a type no message class answers to, a subscription refused) is
        listed with the reason and the others are followed all the same."""
        # a graph that cannot be read ends the round: the supervisor logs it once and runs the loop again
        graph = {name: types for name, types in self.node.get_topic_names_and_types() if types}
        me = self.node.get_name()
        relayed = self.relayed()
        for name, types in graph.items():
            if not self.watch.filter.wants(name):
                continue
            try:
                self._look_at(name, types[0], me, relayed)
            except Exception as exc:  # this topic only: the next look tries it again
                self._unreadable(name, types[0], exc)
        for name in [n for n in self._subs if n not in graph]:
            _, _, sub, _ = self._subs.pop(name)
            if sub is not None:
                self.node.destroy_subscription(sub)
            self.watch.forget(name)
        for name in [n for n in self._shared if n not in graph]:
            del self._shared[name]
            self.watch.forget(name)
        for name in [n for n in self._unread if n not in graph]:
            del self._unread[name]
            self.watch.forget(name)

    def _look_at(self, name: str, graph_type: str, me: str, relayed: dict[str, tuple[str, bool]]) -> None:
        type_name = normalize_type(graph_type)
        try:
            pubs = [i for i in self.node.get_publishers_info_by_topic(name) if i.node_name != me]
            subs = [i for i in self.node.get_subscriptions_info_by_topic(name) if i.node_name != me]
        except Exception:  # the graph query is best effort: next time
            return
        offered = [_policy(i.qos_profile) for i in pubs]
        requested = [_policy(i.qos_profile) for i in subs]
        nodes = (_node_names(pubs), _node_names(subs))
        self.watch.set_graph(name, len(pubs), len(subs), qos_mismatch(offered, requested), nodes)
        best_effort = any(r == "best_effort" for r, _ in offered)
        if relayed.get(name) == (type_name, best_effort):
            self._share(name, type_name)
            self._unread.pop(name, None)
            return
        self._shared.pop(name, None)  # the relay stopped reading it, or reads it otherwise
        have = self._subs.get(name)
        if have is None or have[:2] != (type_name, best_effort):
            if have is not None:
                del self._subs[name]
                if have[2] is not None:
                    self.node.destroy_subscription(have[2])
            sub, stamped = self._subscribe(name, type_name, best_effort)
            self._subs[name] = (type_name, best_effort, sub, stamped)
            self._unread.pop(name, None)  # after a success only: a refusal is warned once, not each look

    def _unreadable(self, topic: str, graph_type: str, exc: Exception) -> None:
        """List ``topic`` with why it cannot be measured; logged once per topic and reason."""
        reason = f"{CANNOT_READ}: {type(exc).__name__}: {exc}"[:200]
        if self._unread.get(topic) != reason:
            log.warning("topic monitor: %s (%s) %s", topic, graph_type, reason)
            self._unread[topic] = reason
        self.watch.watch(topic, graph_type, unmeasured=reason)

    def _share(self, topic: str, type_name: str) -> None:
        """Measure ``topic`` on the relay's reader: the monitor's own goes (its messages taken first)."""
        if topic in self._shared:
            return
        have = self._subs.get(topic)
        if have is not None and have[2] is not None:
            with contextlib.suppress(Exception):  # as in ``_run``: a handle that went away
                self.take()  # what it holds still counts
            self.node.destroy_subscription(have[2])
        self._subs.pop(topic, None)
        stamped = has_header(message_class(type_name))  # the relay reads it: its type is installed
        self.watch.watch(topic, type_name, stamped=stamped)
        self._shared[topic] = stamped
        log.debug("%s: measured on the relay's reader", topic)

    def _subscribe(
        self, topic: str, type_name: str, best_effort: bool
    ) -> tuple[Subscription[Any] | None, bool]:
        try:
            cls = message_class(type_name)
        except MessageError:
            self.watch.watch(topic, type_name, unmeasured=NOT_INSTALLED)
            return None, False
        stamped = has_header(cls)
        self.watch.watch(topic, type_name, stamped=stamped)
        reliability = ReliabilityPolicy.BEST_EFFORT if best_effort else ReliabilityPolicy.RELIABLE
        qos = QoSProfile(depth=DEPTH, reliability=reliability, durability=DurabilityPolicy.VOLATILE)
        # the callback is never called: the monitor's thread takes the messages (see ``take``)
        return self.node.create_subscription(cls, topic, _never, qos, raw=True), stamped

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        for _, _, sub, _ in self._subs.values():
            if sub is not None:
                self.node.destroy_subscription(sub)
        self._subs.clear()


def _never(raw: bytes) -> None:  # pragma: no cover - the monitor's subscriptions are in no executor
    raise AssertionError("the topic monitor's subscriptions are taken from directly")
