"""The frames of one topic waiting for one client: bounded by count and bytes, oldest dropped.

A message goes out whole or, with ``fragment_size``, as rosbridge ``fragment`` frames one at a time
(:class:`Fragments`), so other topics' frames go between them.
"""

from __future__ import annotations

from collections import deque

TOPIC_QUEUE = 1000  # frames of one topic waiting for one client, when the subscription gives no queue_length
TOPIC_QUEUE_BYTES = 8 * 1024 * 1024  # ...and at most this many bytes of them (at least the newest frame)
TURN_BYTES = 64 * 1024  # what one topic may send in its turn before the next topic's turn

Payload = str | bytes  # a text (JSON) or binary (CBOR) WebSocket frame


class Fragments:
    """One message going out as rosbridge ``fragment`` frames (``fragment_size``), one frame at a time,
    so other topics' frames go between them. The parts are shared by every client that gets them."""

    __slots__ = ("next", "parts", "remaining")

    def __init__(self, parts: list[str]) -> None:
        self.parts = parts
        self.next = 0
        self.remaining = sum(len(p) for p in parts)

    def __len__(self) -> int:
        return self.remaining


class Outbox:
    """The messages of one topic waiting for one client: bounded by count and bytes, oldest dropped
    (never the newest, nor a message whose first fragments are out already)."""

    def __init__(self, topic: str, limit: int = TOPIC_QUEUE, max_bytes: int = TOPIC_QUEUE_BYTES) -> None:
        self.topic = topic
        self.limit = limit
        self.max_bytes = max_bytes
        self.frames: deque[Payload | Fragments] = deque()
        self.bytes = 0
        self.dropped = 0
        self.sent = 0
        self.in_ring = False  # in its client's round-robin of topics with something to send

    def put(self, frame: Payload | Fragments) -> int:
        """Queue ``frame``; returns how many older messages were dropped to make room."""
        self.frames.append(frame)
        self.bytes += len(frame)
        dropped = 0
        while True:
            head = self.frames[0]
            start = 1 if isinstance(head, Fragments) and head.next > 0 else 0  # under way: it stays
            waiting = len(self.frames) - start
            if waiting <= 1 or (waiting <= self.limit and self.bytes <= self.max_bytes):
                break
            victim = self.frames[start]
            del self.frames[start]
            self.bytes -= len(victim)
            dropped += 1
        self.dropped += dropped
        return dropped

    def take(self) -> Payload:
        """The next frame to write: a whole message, or the next fragment of one."""
        head = self.frames[0]
        if isinstance(head, Fragments):
            part = head.parts[head.next]
            head.next += 1
            head.remaining -= len(part)
            self.bytes -= len(part)
            if head.next == len(head.parts):
                self.frames.popleft()
                self.sent += 1
            return part
        self.frames.popleft()
        self.bytes -= len(head)
        self.sent += 1
        return head

    def clear(self) -> None:
        self.frames.clear()
        self.bytes = 0


def next_size(item: Payload | Fragments) -> int:
    """The size of the next frame ``item`` writes: itself, or its next fragment."""
    return len(item.parts[item.next]) if isinstance(item, Fragments) else len(item)
