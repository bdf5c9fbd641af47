"""One owner of a rosbridge link's subscriptions: one server subscription per topic, any number of
local listeners.

Every stream the console takes from rosbridge (odometry, latency reports, the topics screen's echo)
is a *listener* here. The registry keeps exactly one server subscription per topic name, with the
loosest parameters any listener needs (the smallest ``throttle_rate``, the largest ``queue_length``),
and fans each message out to the listeners, each throttled on our side to its own rate. Removing a
listener removes that listener only; the server subscription goes when its last listener does.

Why not ``roslibpy.Topic``: its ``unsubscribe()`` calls ``ros.off(name)`` without a callback, which
drops *every* listener of that topic name in the process — the link's own odometry included when
the topics screen stopped echoing ``/odom``. And roslibpy dispatches incoming messages by topic name,
so two ``Topic`` objects on one name would each get both subscriptions' messages.

Pure: no roslibpy, no Twisted, no Textual. The link gives it a function that writes a rosbridge frame
(``write``), hooks to attach/detach a per-topic dispatcher (``attach``/``detach``), a clock and a
timer (``call_later``) for the trailing message of a throttled listener. Thread-safe: listeners come
and go from the UI thread while messages arrive on the link's thread. A subscribe frame is idempotent
(the same id again only updates the parameters, as rosbridge defines), so a frame sent twice around a
reconnect does no harm.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

Listener = Callable[[dict[str, Any]], None]
Frame = dict[str, Any]


@dataclass
class _Listener:
    callback: Listener
    throttle_s: float
    queue_length: int
    last_at: float = float("-inf")  # when it was last given a message (clock seconds)
    pending: dict[str, Any] | None = None  # the newest message held back by the throttle
    timer: Any = None  # the call_later handle that will deliver ``pending``


@dataclass
class _Stream:
    topic: str
    type_name: str
    sub_id: str
    dispatcher: Callable[[dict[str, Any]], None]
    listeners: dict[int, _Listener] = field(default_factory=dict)
    sent: tuple[int, int] | None = None  # (throttle_rate, queue_length) the server has, None: not sent

    def params(self) -> tuple[int, int]:
        """What the server subscription needs: the fastest rate and the longest queue of any listener."""
        throttle = min(round(x.throttle_s * 1000) for x in self.listeners.values())
        queue = max(x.queue_length for x in self.listeners.values())
        return throttle, queue


class Streams:
    """The link's subscriptions (see the module doc)."""

    def __init__(
        self,
        write: Callable[[Frame], None],
        attach: Callable[[str, Callable[[dict[str, Any]], None]], None] = lambda topic, fn: None,
        detach: Callable[[str, Callable[[dict[str, Any]], None]], None] = lambda topic, fn: None,
        clock: Callable[[], float] = time.monotonic,
        call_later: Callable[[float, Callable[[], None]], Any] | None = None,
    ) -> None:
        self._write = write
        self._attach = attach
        self._detach = detach
        self._clock = clock
        self._call_later = call_later
        self._lock = threading.RLock()
        self._streams: dict[str, _Stream] = {}
        self._connected = False
        self._ids = 0

    # listeners

    def listen(
        self,
        topic: str,
        type_name: str,
        callback: Listener,
        throttle_ms: int = 0,
        queue_length: int = 0,
    ) -> Callable[[], None]:
        """Give ``callback`` the messages of ``topic``, at most one every ``throttle_ms`` (the newest
        held back and delivered when the interval ends). A topic already taken shares its server
        subscription (its type stays the first listener's: the server has one per topic). Returns the
        function that removes this listener, and only it; calling it twice is harmless."""
        if throttle_ms < 0 or queue_length < 0:
            raise ValueError("throttle_ms and queue_length must be >= 0")
        listener = _Listener(callback, throttle_ms / 1000.0, queue_length)
        with self._lock:
            stream = self._streams.get(topic)
            new = stream is None
            if stream is None:
                self._ids += 1
                stream = _Stream(topic, type_name, f"subscribe:{topic}:{self._ids}", lambda m: None)
                stream.dispatcher = self._dispatcher(stream)
                self._streams[topic] = stream
            key = id(listener)
            stream.listeners[key] = listener
            self._sync(stream)
        if new:
            # outside our lock: the link's emitter holds its own lock while it calls a dispatcher
            # (which takes ours), so taking them in the other order here could deadlock
            self._attach(topic, stream.dispatcher)

        def remove() -> None:
            self._remove(stream, key)

        return remove

    def _remove(self, stream: _Stream, key: int) -> None:
        with self._lock:
            listener = stream.listeners.pop(key, None)
            if listener is None:
                return
            self._cancel(listener)
            if stream.listeners:
                self._sync(stream)
                return
            if self._streams.get(stream.topic) is stream:
                del self._streams[stream.topic]
            if self._connected and stream.sent is not None:
                self._write({"op": "unsubscribe", "id": stream.sub_id, "topic": stream.topic})
        self._detach(stream.topic, stream.dispatcher)  # outside our lock, as in ``listen``

    # the connection

    def connected(self) -> None:
        """The link is (again) up: every subscription goes to the server."""
        with self._lock:
            self._connected = True
            for stream in self._streams.values():
                stream.sent = None
                self._sync(stream)

    def disconnected(self) -> None:
        """The link went down: the server forgot our subscriptions; they are sent again on
        :meth:`connected`. Held-back messages are dropped (they are stale by then)."""
        with self._lock:
            self._connected = False
            for stream in self._streams.values():
                stream.sent = None
                for listener in stream.listeners.values():
                    self._cancel(listener)

    def _sync(self, stream: _Stream) -> None:
        """Send the subscribe frame when the server's parameters differ from what the listeners need
        (the same id: the server updates that subscription)."""
        if not self._connected:
            return
        params = stream.params()
        if params == stream.sent:
            return
        stream.sent = params
        self._write(
            {
                "op": "subscribe",
                "id": stream.sub_id,
                "topic": stream.topic,
                "type": stream.type_name,
                "throttle_rate": params[0],
                "queue_length": params[1],
            }
        )

    # messages

    def _dispatcher(self, stream: _Stream) -> Callable[[dict[str, Any]], None]:
        def dispatch(msg: dict[str, Any]) -> None:
            self.deliver(stream, msg)

        return dispatch

    def dispatch(self, topic: str, msg: dict[str, Any]) -> None:
        """A message of ``topic`` arrived (for a link that routes by name itself)."""
        stream = self._streams.get(topic)
        if stream is not None:
            self.deliver(stream, msg)

    def deliver(self, stream: _Stream, msg: dict[str, Any]) -> None:
        now = self._clock()
        due: list[Listener] = []
        with self._lock:
            for listener in list(stream.listeners.values()):
                if listener.throttle_s <= 0 or now - listener.last_at >= listener.throttle_s:
                    self._cancel(listener)
                    listener.last_at = now
                    due.append(listener.callback)
                else:
                    listener.pending = msg  # the newest wins; delivered when its interval ends
                    if listener.timer is None and self._call_later is not None:
                        wait = listener.last_at + listener.throttle_s - now
                        listener.timer = self._call_later(wait, self._flusher(stream, listener))
        for callback in due:  # outside the lock: a listener may add or remove listeners (and so one
            callback(msg)  # removed by another thread meanwhile may still get this last message)

    def _flusher(self, stream: _Stream, listener: _Listener) -> Callable[[], None]:
        def flush() -> None:
            with self._lock:
                listener.timer = None
                msg, listener.pending = listener.pending, None
                if msg is None or stream.listeners.get(id(listener)) is not listener:
                    return
                listener.last_at = self._clock()
            listener.callback(msg)

        return flush

    @staticmethod
    def _cancel(listener: _Listener) -> None:
        """Drop the held-back message. Its timer is left to fire and find nothing: a Twisted timer
        may be cancelled only on the reactor's thread, and listeners go from the UI's."""
        listener.pending = None

    # what is there

    def subscriptions(self) -> dict[str, tuple[str, int, int, int]]:
        """Topic → (type, throttle_rate, queue_length, listeners): what the server is asked for."""
        with self._lock:
            return {s.topic: (s.type_name, *s.params(), len(s.listeners)) for s in self._streams.values()}
