"""Topic ops: ``advertise``, ``unadvertise``, ``publish``, ``subscribe`` (``throttle_rate``,
``queue_length``, ``compression``, ``fragment_size``), ``unsubscribe``; and the bus's messages handed
to each subscription's outbox.

Several subscriptions of one client to one topic (requests with several ids) are merged, as rosbridge
does: the smallest ``throttle_rate`` and ``queue_length``, the strongest ``compression``, the smallest
``fragment_size``. A topic name is resolved as rosbridge's node resolves it (``exposure.py``: ``odom``
under the bridge's namespace); a subscription is kept under the name as the client gave it, which its
frames carry back. ``throttle_rate`` ≤ 1 h, ``queue_length`` ≤ 10⁶.
"""

from __future__ import annotations

import asyncio
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Any

from ..bus import Bus
from . import frames
from .client import Client
from .encoding import COMPRESSIONS, MIN_FRAGMENT, Encoder
from .exposure import Exposure
from .frames import TRANSPORT_MAX_FRAME, BadFrame, Frame
from .outbox import TOPIC_QUEUE, Fragments, Payload

MAX_THROTTLE_MS = 3_600_000
MAX_QUEUE_LENGTH = 1_000_000


@dataclass
class Subscription:
    """One client's subscription to one topic (requests with several ids are merged, as rosbridge does)."""

    topic: str  # resolved: /odom
    name: str  # as the client gave it (odom): the key of its subscriptions, and its frames' topic
    # id -> (throttle_ms, queue_length, compression, fragment_size or 0)
    requests: dict[Any, tuple[int, int, str, int]] = field(default_factory=dict)
    type_name: str | None = None
    unsubscribe: Callable[[], None] | None = None
    last_sent: float = -1e18
    pending: deque[Payload | Fragments] = field(default_factory=deque)
    timer: asyncio.TimerHandle | None = None

    @property
    def throttle_s(self) -> float:
        return min(r[0] for r in self.requests.values()) / 1000.0

    @property
    def queue_length(self) -> int:
        return min(r[1] for r in self.requests.values())

    @property
    def compression(self) -> str:
        """The strongest of the requests' (``COMPRESSIONS``' order), for all of them, as rosbridge."""
        return max((r[2] for r in self.requests.values()), key=COMPRESSIONS.index)

    @property
    def fragment_size(self) -> int:
        """The smallest of the requests' (0: none); JSON frames longer than it go out in fragments."""
        sizes = [r[3] for r in self.requests.values() if r[3]]
        return min(sizes) if sizes else 0

    @property
    def outbox_limit(self) -> int:
        """The client's outgoing queue for the topic: ``queue_length`` frames (1: only the latest);
        without one, ``TOPIC_QUEUE``."""
        return self.queue_length or TOPIC_QUEUE

    def close(self) -> None:
        """Off the bus, and no throttled frame left to send."""
        if self.unsubscribe:
            self.unsubscribe()
        if self.timer:
            self.timer.cancel()


class TopicRoom:
    def __init__(
        self, bus: Bus, exposure: Exposure, encoder: Encoder, clients: set[Client], client_queue: int
    ) -> None:
        self.bus = bus
        self.exposure = exposure
        self.encoder = encoder
        self.clients = clients  # the endpoint's: a topic's frames are forgotten once none subscribes
        self.client_queue = client_queue

    # -- ops ----------------------------------------------------------------------------------------
    def advertise(self, client: Client, frame: Frame) -> None:
        topic = self.exposure.topic(frame)
        type_name = frames.field(frame, "type", str)
        latch = frames.field(frame, "latch", bool, required=False) is True  # rosbridge's field
        if topic in client.advertised:
            client.advertised[topic] = self.bus.declare(topic, type_name)
        else:
            client.advertised[topic] = self.bus.advertise(topic, type_name, latch=latch)

    def unadvertise(self, client: Client, frame: Frame) -> None:
        topic = self.exposure.name(frame)
        if client.advertised.pop(topic, None) is not None:
            self.bus.unadvertise(topic)

    def publish(self, client: Client, frame: Frame) -> None:
        topic = self.exposure.topic(frame)
        msg = frame.get("msg", {})
        type_name = client.advertised.get(topic) or self.bus.type_of(topic)
        if type_name is None:
            raise BadFrame(f"cannot infer the type of {topic}: advertise it first")
        self.bus.publish(topic, msg, type_name)

    def subscribe(self, client: Client, frame: Frame) -> None:
        topic = self.exposure.topic(frame)
        type_name = frames.field(frame, "type", str, required=False)
        throttle = frames.field(frame, "throttle_rate", int, required=False) or 0
        queue_length = frames.field(frame, "queue_length", int, required=False) or 0
        if not 0 <= throttle <= MAX_THROTTLE_MS:
            raise BadFrame(f"throttle_rate must be 0..{MAX_THROTTLE_MS} ms")
        if not 0 <= queue_length <= MAX_QUEUE_LENGTH:
            raise BadFrame(f"queue_length must be 0..{MAX_QUEUE_LENGTH}")
        queue_length = min(queue_length, self.client_queue)
        compression = frames.field(frame, "compression", str, required=False) or "none"
        if compression not in COMPRESSIONS:
            raise BadFrame(f"compression must be one of {', '.join(COMPRESSIONS)}, got {compression[:20]!r}")
        fragment_size = frames.field(frame, "fragment_size", int, required=False) or 0
        if fragment_size and not MIN_FRAGMENT <= fragment_size <= TRANSPORT_MAX_FRAME:
            raise BadFrame(f"fragment_size must be {MIN_FRAGMENT}..{TRANSPORT_MAX_FRAME} characters")
        if compression == "cbor-raw" and not self.encoder.serialises:
            raise BadFrame(
                "compression cbor-raw needs a transport that serialises messages (--transport ros)"
            )
        if type_name is not None:
            self.bus.declare(topic, type_name)
        elif self.bus.type_of(topic) is None:
            raise BadFrame(f"cannot subscribe to {topic}: type unknown; give 'type'")
        # keyed by the name as given, which its frames carry back (rosbridge's: a client that subscribes
        # "odom" gets frames of "odom", and roslibpy and roslibjs dispatch them by that name)
        name = frames.field(frame, "topic", str)
        sub = client.subs.get(name)
        if sub is None:
            sub = Subscription(topic, name)
            client.subs[name] = sub
            sub.unsubscribe = self.bus.subscribe(topic, partial(self._deliver, client, sub))
        sub.requests[frame.get("id", f"_anon{len(sub.requests)}")] = (
            throttle,
            queue_length,
            compression,
            fragment_size,
        )
        sub.type_name = self.bus.type_of(topic)
        client.outbox(name, sub.outbox_limit)

    def unsubscribe(self, client: Client, frame: Frame) -> None:
        self.exposure.name(frame)  # a valid name
        topic = frames.field(frame, "topic", str)  # as given when subscribing (the subscription's key)
        sub = client.subs.get(topic)
        if sub is None:
            return
        req_id = frame.get("id")
        if req_id is not None and req_id in sub.requests:
            del sub.requests[req_id]
        elif req_id is None or isinstance(req_id, (dict, list)):
            sub.requests.clear()
        if not sub.requests:
            sub.close()
            del client.subs[topic]
            client.drop_outbox(topic)
            self._forget_frames(topic)
        else:
            client.outbox(topic, sub.outbox_limit)

    def leave(self, client: Client) -> None:
        """``client`` is gone: its subscriptions, outboxes and advertisements with it."""
        for sub in client.subs.values():
            sub.close()
        topics = list(client.subs)
        client.subs.clear()
        for topic in list(client.boxes):
            client.drop_outbox(topic)
        for topic in topics:
            self._forget_frames(topic)
        for topic in client.advertised:
            self.bus.unadvertise(topic)
        client.advertised.clear()

    # -- the bus's messages to the subscriptions -----------------------------------------------------
    def _forget_frames(self, topic: str) -> None:
        if not any(topic in c.subs for c in self.clients if not c.closed):
            self.encoder.forget(topic)

    def _deliver(self, client: Client, sub: Subscription, msg: dict[str, Any]) -> None:
        if client.subs.get(sub.name) is not sub:
            return  # unsubscribed while the bus was fanning this message out: no outbox to refill
        frame = self.encoder.encode(sub.name, sub.compression, sub.type_name, msg, sub.fragment_size)
        throttle = sub.throttle_s
        if throttle <= 0:
            client.enqueue(sub.name, frame)
            return
        now = time.monotonic()
        if now - sub.last_sent >= throttle and not sub.pending:
            sub.last_sent = now
            client.enqueue(sub.name, frame)
            return
        qlen = sub.queue_length
        if qlen <= 0:
            return
        sub.pending.append(frame)
        while len(sub.pending) > qlen:
            sub.pending.popleft()
        if sub.timer is None:
            delay = max(0.0, sub.last_sent + throttle - now)
            sub.timer = asyncio.get_running_loop().call_later(delay, self._flush, client, sub)

    def _flush(self, client: Client, sub: Subscription) -> None:
        sub.timer = None
        if client.closed or not sub.pending:
            return
        sub.last_sent = time.monotonic()
        client.enqueue(sub.name, sub.pending.popleft())
        if sub.pending:
            sub.timer = asyncio.get_running_loop().call_later(sub.throttle_s, self._flush, client, sub)
