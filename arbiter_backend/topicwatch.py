"""The backend's topic monitor: every topic's rate, bandwidth, delay and age, for ``GET /api/topics``.

``TopicWatch`` holds one ``arbiter_core.topicstats.TopicWindow`` per watched topic behind a lock (in ROS
mode messages arrive on the monitor's thread, the API reads on the asyncio loop), and samples each
topic's rate once a second for its history (``sample``, called by either transport's own loop). What
feeds it is the transport's: ``EmbeddedTopics`` taps every publish on the embedded bus (size = the
message's JSON, the only form it has there); ``ros.topicwatch.RosTopics`` subscribes to every topic on
the graph with raw (serialized) messages.
"""

from __future__ import annotations

import fnmatch
import json
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeGuard

from arbiter_core.topicstats import WINDOW_S, TopicFigures, TopicWindow, unknown

from .bus import TopicBus
from .supervise import Supervisor, WorkerRecord


@dataclass(frozen=True)
class TopicFilter:
    """Which topics are watched: those matching any ``include`` glob and no ``exclude`` glob."""

    include: tuple[str, ...] = ("*",)
    exclude: tuple[str, ...] = ()

    @classmethod
    def parse(cls, include: str | None, exclude: str | None) -> TopicFilter:
        def globs(text: str | None) -> tuple[str, ...]:
            return tuple(g.strip() for g in (text or "").split(",") if g.strip())

        return cls(globs(include) or ("*",), globs(exclude))

    def wants(self, topic: str) -> bool:
        return any(fnmatch.fnmatchcase(topic, g) for g in self.include) and not any(
            fnmatch.fnmatchcase(topic, g) for g in self.exclude
        )


@dataclass
class _Graph:
    """What the graph says of a topic, refreshed by the transport (not per message)."""

    publishers: int = 0
    subscribers: int = 0
    qos_note: str | None = None
    nodes: tuple[tuple[str, ...], tuple[str, ...]] = ((), ())  # publishing, subscribing node names


@dataclass
class TopicWatch:
    filter: TopicFilter = field(default_factory=TopicFilter)
    window_s: float = WINDOW_S
    clock: Callable[[], float] = time.monotonic
    _lock: threading.Lock = field(default_factory=threading.Lock)
    _windows: dict[str, TopicWindow] = field(default_factory=dict)
    _graph: dict[str, _Graph] = field(default_factory=dict)
    _held: dict[str, str] = field(default_factory=dict)  # worker -> why its topics' states are unknown

    def hold(self, worker: str, reason: str) -> None:
        """``worker``, which feeds this watch, failed: every measured topic is ``unknown`` (with
        ``reason`` as its note) until :meth:`release`, never ``silent`` for want of a reader."""
        with self._lock:
            self._held[worker] = reason

    def release(self, worker: str) -> None:
        with self._lock:
            self._held.pop(worker, None)

    def watch(self, topic: str, type_name: str, stamped: bool = False, unmeasured: str | None = None) -> bool:
        """Start watching ``topic`` (if the filter wants it); False when it does not."""
        if not self.filter.wants(topic):
            return False
        with self._lock:
            w = self._windows.get(topic)
            if w is None or w.type != type_name:
                w = TopicWindow(topic, type_name, self.window_s, stamped, created=self.clock())
                self._windows[topic] = w
            w.stamped, w.unmeasured = stamped, unmeasured
        return True

    def forget(self, topic: str) -> None:
        with self._lock:
            self._windows.pop(topic, None)
            self._graph.pop(topic, None)

    def watched(self) -> set[str]:
        with self._lock:
            return set(self._windows)

    def note(
        self,
        topic: str,
        size: int,
        delay_s: float | None = None,
        bad_stamp: bool = False,
        at: float | None = None,
    ) -> None:
        """One message of ``topic``: its size and, for a stamped type, its delay or a malformed stamp;
        ``at``: when it was received on ``clock`` (default: now)."""
        now = self.clock() if at is None else at
        with self._lock:
            w = self._windows.get(topic)
            if w is None:
                return
            w.add(now, size, delay_s)
            if bad_stamp:
                w.bad_stamp()

    def set_graph(
        self,
        topic: str,
        publishers: int,
        subscribers: int,
        qos_note: str | None = None,
        nodes: tuple[tuple[str, ...], tuple[str, ...]] = ((), ()),
    ) -> None:
        with self._lock:
            self._graph[topic] = _Graph(publishers, subscribers, qos_note, nodes)

    def sample(self) -> None:
        """Each topic's rate history (one sample a second, ``TopicWindow.sample``): the transports call this
        a few times a second whether or not anyone asks, so the history covers the last minute the moment
        a console opens its topics screen."""
        now = self.clock()
        with self._lock:
            for w in self._windows.values():
                w.sample(now)

    def figures(self) -> list[TopicFigures]:
        return self.snapshot()[0]

    def snapshot(self) -> tuple[list[TopicFigures], str | None]:
        """Every topic's figures and, while held, why their states are ``unknown`` (read together: the
        answer and the fleet's payload never say one without the other)."""
        now = self.clock()
        with self._lock:
            held = "; ".join(self._held.values()) or None
            out = []
            for name, w in sorted(self._windows.items()):
                g = self._graph.get(name, _Graph())
                f = w.figures(now, g.publishers, g.subscribers, g.qos_note, g.nodes)
                out.append(f if held is None else unknown(f, held))
        return out, held

    def answer(self) -> dict[str, Any]:
        """The body of ``GET /api/topics``: ``interrupted`` says why the states are ``unknown`` (null: they
        are not)."""
        figures, held = self.snapshot()
        return {"window_s": self.window_s, "interrupted": held, "topics": [f.to_json() for f in figures]}


def follow(supervisor: Supervisor, worker: str, watch: TopicWatch, label: str) -> None:
    """While ``worker`` (which feeds ``watch``) is restarting or failed, ``watch`` is held:
    ``"<label> restarted: <error>"`` (or ``failed``); released at its first round after a restart."""

    def changed(w: WorkerRecord) -> None:
        if w.state in ("restarting", "failed") and w.error is not None:
            watch.hold(worker, f"{label} {'failed' if w.state == 'failed' else 'restarted'}: {w.error}"[:200])
        elif w.state == "running":
            watch.release(worker)

    supervisor.listen(worker, changed)


def _finite_number(v: object) -> TypeGuard[int | float]:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def header_delay(msg: dict[str, Any], wall_now: float) -> tuple[float | None, bool]:
    """(now - header.stamp, malformed) for a rosbridge-JSON message; (None, False) without a header."""
    header = msg.get("header")
    if not isinstance(header, dict) or "stamp" not in header:
        return None, False
    stamp = header.get("stamp")
    if not isinstance(stamp, dict):
        return None, True
    sec, nsec = stamp.get("sec", stamp.get("secs")), stamp.get("nanosec", stamp.get("nsecs", 0))
    if not (_finite_number(sec) and _finite_number(nsec)) or not 0 <= nsec < 1e9:
        return None, True
    return wall_now - (sec + nsec / 1e9), False


class EmbeddedTopics:
    """Feeds a ``TopicWatch`` from the embedded bus: every publish, whatever its topic. The counts are
    read from the bus when an answer is asked for, not per message."""

    def __init__(self, bus: TopicBus, watch: TopicWatch) -> None:
        self.bus = bus
        self.watch = watch
        self._heard: set[str] = set()  # topics that have carried a message (their stamped-ness is known)
        bus.taps.append(self._on_publish)
        self.refresh()  # the topics declared so far are watched from now: one that waits is on demand

    def _on_publish(self, topic: str, type_name: str, msg: dict[str, Any]) -> None:
        if topic not in self._heard:
            self._heard.add(topic)
            self.watch.watch(topic, type_name, stamped="header" in msg)
        size = len(json.dumps(msg, separators=(",", ":"), default=str))
        delay, bad = header_delay(msg, time.time())
        self.watch.note(topic, size, delay, bad)

    def answer(self) -> dict[str, Any]:
        self.refresh()
        return self.watch.answer()

    def tick(self) -> None:
        """A few times a second (the backend's task): topics declared meanwhile, and the rate history."""
        self.refresh()
        self.watch.sample()

    def refresh(self) -> None:
        """Every topic the bus knows (declared, advertised or published), with its counts: advertisers
        (the backend's own publishers among them) and subscribers."""
        watched = self.watch.watched()
        for name, type_name in self.bus.topics():
            if name not in watched and not self.watch.watch(name, type_name):
                continue  # the filter does not want it
            self.watch.set_graph(name, self.bus.publisher_count(name), self.bus.subscriber_count(name))
