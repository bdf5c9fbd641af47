"""One WebSocket client's state: its replies, one outbox per topic, the status level it asked for, its
calls and goals under way, and the pacer of its big frames.

Outgoing frames wait in one bounded queue per (client, topic) (``Outbox``), plus one for the client's
replies (status, service_response), which go first. The client's writer task (``wire.writer``) takes
the topics with something to send in turn (round-robin; a turn sends up to ``TURN_BYTES``, at least
one message), and awaits aiohttp's drain after each write, so a client takes frames as fast as its
socket drains and no faster. A big topic (camera frames) therefore never starves a small one: a small
message waits for at most the one big frame being written. A full queue drops its oldest frame
(counted per topic, logged, and in ``/api/health``); a slow client loses old frames of the topic that
overflows, never another topic's messages or their order, and never blocks the bus or the other
clients. A client that lags has its big frames paced below the rate it reads at (``pacing``), so the
buffers a small message waits behind stay nearly empty.
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import time
from collections import deque
from collections.abc import Callable, Coroutine
from typing import TYPE_CHECKING, Any

from aiohttp import web

from .. import pacing
from ..pacing import PACED_BYTES, Pacer
from .frames import BadFrame, dumps
from .outbox import TOPIC_QUEUE, TURN_BYTES, Fragments, Outbox, Payload, next_size

if TYPE_CHECKING:
    from .topics import Subscription

log = logging.getLogger(__name__)

CLIENT_QUEUE = 1000  # a client's replies (status, service_response) waiting to be sent
MAX_CALLS = 256  # service calls and goals one client may have under way at once
LEVELS = ("info", "warning", "error", "none")


class Client:
    """One WebSocket client: its replies and per-topic outboxes, its subscriptions, advertisements,
    calls and goals under way, and its pacer."""

    _ids = itertools.count(1)

    def __init__(
        self,
        ws: web.WebSocketResponse,
        queue_size: int,
        remote: str | None = None,
        paced_wait: float | None = pacing.WAIT_S,
    ) -> None:
        self.id = next(self._ids)
        self.ws = ws
        self.remote = remote
        self.out: deque[Payload] = deque(maxlen=queue_size)  # replies: sent before any topic's frames
        self.boxes: dict[str, Outbox] = {}
        self.ring: deque[Outbox] = deque()  # the outboxes with something to send, in turn
        self.wakeup = asyncio.Event()
        self.replies_dropped = 0
        self.dropped_by_topic: dict[str, int] = {}  # kept after an unsubscribe, for the final log line
        self.advertised: dict[str, str] = {}
        self.subs: dict[str, Subscription] = {}
        self.level = "error"
        self.closed = False
        self.authenticated = True
        self.kick: tuple[int, str] | None = None  # close with (code, reason) once the queue is sent
        self.calls: set[asyncio.Task[None]] = set()  # service calls and goals under way
        self.goals: dict[Any, Callable[[], None]] = {}  # the goals it sent, by its id -> cancel
        self.last_rx = 0.0  # loop time of the last frame (pong included) received from the client
        self.pacer = Pacer(paced_wait)  # its big frames, paced below the rate it reads at once it lags

    def room_for_call(self) -> None:
        """BadFrame when ``MAX_CALLS`` calls and goals are under way for this client already."""
        if len(self.calls) >= MAX_CALLS:
            raise BadFrame(f"{MAX_CALLS} calls and goals are under way for this client already")

    def track(self, work: Coroutine[Any, Any, None]) -> asyncio.Task[None]:
        """Run a call or goal for this client without holding its other frames; cancelled if it leaves."""
        task = asyncio.get_running_loop().create_task(work)
        self.calls.add(task)
        task.add_done_callback(self.calls.discard)
        return task

    @property
    def dropped(self) -> int:
        return self.replies_dropped + sum(self.dropped_by_topic.values())

    def send(self, frame: Payload) -> None:
        """A reply (status, service_response): ahead of every topic's frames."""
        if self.closed:
            return
        if len(self.out) == self.out.maxlen:
            self.replies_dropped += 1
        self.out.append(frame)
        self.wakeup.set()

    def outbox(self, topic: str, limit: int = TOPIC_QUEUE) -> Outbox:
        box = self.boxes.get(topic)
        if box is None:
            box = self.boxes[topic] = Outbox(topic, limit)
        else:
            box.limit = limit
        return box

    def drop_outbox(self, topic: str) -> None:
        box = self.boxes.pop(topic, None)
        if box is not None:
            box.clear()
            if box.in_ring:
                self.ring.remove(box)
                box.in_ring = False

    def enqueue(self, topic: str, frame: Payload | Fragments) -> None:
        """A message of ``topic``: into that topic's outbox, its oldest frame dropped when full."""
        if self.closed:
            return
        box = self.boxes.get(topic) or self.outbox(topic)
        if len(frame) >= PACED_BYTES:  # only big frames count towards the pace (no clock read otherwise)
            self.pacer.offered(len(frame), time.monotonic())
        dropped = box.put(frame)
        if dropped:
            before = self.dropped_by_topic.get(topic, 0)
            self.dropped_by_topic[topic] = before + dropped
            if before == 0:
                log.info(
                    "client %d reads %s slower than it comes: dropping its oldest frames (queue of %d)",
                    self.id,
                    topic,
                    box.limit,
                )
        if not box.in_ring:
            box.in_ring = True
            self.ring.append(box)
        self.wakeup.set()

    def next_turn(self, now: float | None = None) -> list[Payload]:
        """What to write next: the oldest reply, or the next topic's turn (up to ``TURN_BYTES``). With
        ``now`` (loop time), a topic whose next frame is big waits its turn until the client's pacer
        allows one (``pacing``); [] then when only such topics have something to send."""
        if self.out:
            return [self.out.popleft()]
        if not self.ring:
            return []
        box = self.ring.popleft()
        if now is not None and now < self.pacer.next_at():
            for _ in range(len(self.ring) + 1):
                if next_size(box.frames[0]) < PACED_BYTES:
                    break
                self.ring.append(box)
                box = self.ring.popleft()
            else:
                self.ring.appendleft(box)  # every topic waits for the pacer; the order is unchanged
                return []
        frames: list[Payload] = []
        size = 0
        while box.frames and (not frames or size + next_size(box.frames[0]) <= TURN_BYTES):
            frame = box.take()
            frames.append(frame)
            size += len(frame)
        if box.frames:
            self.ring.append(box)
        else:
            box.in_ring = False
        return frames

    def stats(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "remote": self.remote,
            "replies_dropped": self.replies_dropped,
            # the rate it was measured reading at while it lagged (its big frames paced below it); null:
            # it never lagged
            "read_bytes_per_s": None if self.pacer.rate is None else round(self.pacer.rate),
            "paced": self.pacer.paced,  # its big frames are sent below that rate (it cannot keep up)
            "topics": {
                topic: {
                    "queued": len(box.frames),
                    "queue_length": box.limit,
                    "sent": box.sent,
                    "dropped": self.dropped_by_topic.get(topic, 0),
                }
                for topic, box in self.boxes.items()
            },
        }

    def status(self, level: str, msg: str, req_id: Any = None) -> None:
        if self.level == "none" or LEVELS.index(level) < LEVELS.index(self.level):
            return
        frame: dict[str, Any] = {"op": "status", "level": level, "msg": msg}
        if req_id is not None:
            frame["id"] = req_id
        self.send(dumps(frame))
