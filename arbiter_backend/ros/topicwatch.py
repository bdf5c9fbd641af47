"""The topic monitor on DDS: every topic on the graph, measured from serialized messages.

One node (``arbiter_topic_monitor``) looks at the graph every ``GRAPH_S`` seconds; for each topic the
filter wants it makes a subscription with ``raw=True`` — the callback gets the CDR bytes, never a
deserialised message — best effort and volatile (as ``ros2 topic hz`` subscribes: it matches every
publisher, reliable or not, and gets no history that would skew the rate). Size is ``len(bytes)``; for
a type whose first field is a ``std_msgs/Header`` the stamp is read from the bytes right after the
4-byte encapsulation header (``int32 sec, uint32 nanosec``, in the byte order the encapsulation names),
so a 30 Hz camera costs one small unpack per frame. A type not installed here cannot be subscribed
(rclpy has no generic subscription): it is listed with its type, counts and "type not installed here".
"""

from __future__ import annotations

import contextlib
import logging
import struct
import time
from typing import Any

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.subscription import Subscription

from arbiter_core.msgtypes import MessageError, normalize_type
from arbiter_core.topicstats import NOT_INSTALLED, qos_mismatch

from ..topicwatch import TopicWatch
from .convert import message_class

log = logging.getLogger(__name__)

NODE_NAME = "arbiter_topic_monitor"
GRAPH_S = 1.0  # how often the graph is looked at: topics that appear are watched within a second
DEPTH = 100  # a burst of a fast topic between two executor passes is not dropped by the reader

_STAMP_LE, _STAMP_BE = struct.Struct("<iI"), struct.Struct(">iI")


def cdr_stamp(raw: bytes) -> float | None:
    """``header.stamp`` of a serialized message whose first field is a Header, in seconds; None when the
    bytes cannot hold one (too short, nanoseconds out of range)."""
    if len(raw) < 12:
        return None
    sec, nsec = (_STAMP_LE if raw[1] & 1 else _STAMP_BE).unpack_from(raw, 4)
    if nsec >= 1_000_000_000:
        return None
    return sec + nsec / 1e9


def has_header(cls: Any) -> bool:
    """The message's first field is a ``std_msgs/Header`` (as ``ros2 topic delay`` requires)."""
    fields = list(cls.get_fields_and_field_types().items())
    return bool(fields) and fields[0][1] == "std_msgs/Header"


def _policy(profile: QoSProfile) -> tuple[str, str]:
    r = "best_effort" if profile.reliability == ReliabilityPolicy.BEST_EFFORT else "reliable"
    d = "transient_local" if profile.durability == DurabilityPolicy.TRANSIENT_LOCAL else "volatile"
    return r, d


class RosTopics:
    def __init__(self, node: Node, watch: TopicWatch) -> None:
        self.node = node
        self.watch = watch
        self._subs: dict[str, tuple[str, Subscription | None]] = {}  # topic -> (type, subscription)
        self.timer = node.create_timer(GRAPH_S, self.look)

    def answer(self) -> dict[str, Any]:
        return self.watch.answer()

    def look(self) -> None:  # executor thread
        """Follow the graph: watch topics that appeared, drop those gone, refresh counts and QoS notes."""
        try:
            graph = {name: types for name, types in self.node.get_topic_names_and_types() if types}
        except Exception:  # the graph query is best effort
            log.exception("reading the graph failed")
            return
        me = self.node.get_name()
        for name, types in graph.items():
            if not self.watch.filter.wants(name):
                continue
            type_name = normalize_type(types[0])
            have = self._subs.get(name)
            if have is None or have[0] != type_name:
                if have is not None and have[1] is not None:
                    self.node.destroy_subscription(have[1])
                self._subs[name] = (type_name, self._subscribe(name, type_name))
            with contextlib.suppress(Exception):
                pubs = [i for i in self.node.get_publishers_info_by_topic(name) if i.node_name != me]
                subs = [i for i in self.node.get_subscriptions_info_by_topic(name) if i.node_name != me]
                offered = [_policy(i.qos_profile) for i in pubs]
                requested = [_policy(i.qos_profile) for i in subs]
                self.watch.set_graph(name, len(pubs), len(subs), qos_mismatch(offered, requested))
        for name in [n for n in self._subs if n not in graph]:
            _, sub = self._subs.pop(name)
            if sub is not None:
                self.node.destroy_subscription(sub)
            self.watch.forget(name)

    def _subscribe(self, topic: str, type_name: str) -> Subscription | None:
        try:
            cls = message_class(type_name)
        except MessageError:
            self.watch.watch(topic, type_name, unmeasured=NOT_INSTALLED)
            return None
        stamped = has_header(cls)
        self.watch.watch(topic, type_name, stamped=stamped)
        qos = QoSProfile(
            depth=DEPTH, reliability=ReliabilityPolicy.BEST_EFFORT, durability=DurabilityPolicy.VOLATILE
        )
        note = self.watch.note
        if stamped:

            def on_stamped(raw: bytes) -> None:
                stamp = cdr_stamp(raw)
                if stamp is None:
                    note(topic, len(raw), None, True)
                else:
                    note(topic, len(raw), time.time() - stamp)

            callback = on_stamped
        else:

            def on_message(raw: bytes) -> None:
                note(topic, len(raw))

            callback = on_message
        return self.node.create_subscription(cls, topic, callback, qos, raw=True)

    def close(self) -> None:
        for _, sub in self._subs.values():
            if sub is not None:
                self.node.destroy_subscription(sub)
        self._subs.clear()
