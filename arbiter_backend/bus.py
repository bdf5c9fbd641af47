"""The in-process topic bus: the embedded stand-in for the ROS graph.

Messages travel in rosbridge's JSON form (dicts). Callbacks run synchronously
on the publisher's thread (in the backend, the one asyncio loop), so a command
reaches the tracker without a queue hop. A callback that raises is logged and
skipped; it never breaks delivery to the others.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from arbiter_core.msgtypes import MessageError, check_message, normalize_type

if TYPE_CHECKING:
    from .rosapi import Graph

log = logging.getLogger(__name__)

Callback = Callable[[dict[str, Any]], None]


class TypeClash(MessageError):
    """A topic was used with a type other than the one it has."""


class Bus(Protocol):
    """What the rosbridge endpoint needs of a bus: this module's TopicBus, or ``ros.bus.RosBus`` (DDS)."""

    def declare(self, topic: str, type_name: str) -> str: ...
    def advertise(self, topic: str, type_name: str, latch: bool = False) -> str: ...
    def unadvertise(self, topic: str) -> None: ...
    def type_of(self, topic: str) -> str | None: ...
    def topics(self) -> list[tuple[str, str]]: ...
    def subscribe(
        self, topic: str, callback: Callback, type_name: str | None = None
    ) -> Callable[[], None]: ...
    def publish(self, topic: str, msg: Any, type_name: str | None = None) -> dict[str, Any]: ...


# -- what a bus may have beyond Bus: checked with isinstance, never probed by name, so that a rename fails
# the type check (ros/bus.py states that RosBus has both), as the console's link/base.py does -----------
@runtime_checkable
class GraphBus(Protocol):
    """A bus on a ROS graph (``ros.bus.RosBus``): rosapi answers from the live graph, any service on it is
    called, and what clients provide or send goals to goes through rclpy (``interfaces``)."""

    @property
    def graph(self) -> Graph: ...
    @property
    def interfaces(self) -> Any: ...  # ros.interfaces.RosInterfaces (rclpy's): set by the ROS backend


@runtime_checkable
class ConvertingBus(Protocol):
    """A bus that carries ROS messages (``ros.bus.RosBus``): their JSON form made on first use, rosbridge's
    CBOR form (typed arrays, byte strings) and their CDR bytes (``cbor-raw``) with the time received."""

    def json_form(self, msg: dict[str, Any]) -> dict[str, Any]: ...
    def cbor_values(self, type_name: str | None, msg: dict[str, Any]) -> dict[str, Any]: ...
    def cdr(self, type_name: str | None, msg: dict[str, Any]) -> tuple[bytes, int]: ...


class TopicBus:
    def __init__(self) -> None:
        self._types: dict[str, str] = {}
        self._subs: dict[str, list[Callback]] = {}
        self.published = 0
        # topics advertised with ``latch``: their last message, handed to each subscriber that comes
        # later (and only to it), as a transient-local publisher's sample reaches a late DDS reader
        self._latch: set[str] = set()
        self._latched: dict[str, dict[str, Any]] = {}
        self._advertisers: dict[str, int] = {}
        # called with (topic, type, message) on every publish, after delivery: the topic monitor
        self.taps: list[Callable[[str, str, dict[str, Any]], None]] = []

    def declare(self, topic: str, type_name: str) -> str:
        """Give ``topic`` a type (normalised), or check it against the one it has."""
        t = normalize_type(type_name)
        have = self._types.get(topic)
        if have is not None and have != t:
            raise TypeClash(f"topic {topic} has type {have}, not {t}")
        self._types[topic] = t
        return t

    def advertise(self, topic: str, type_name: str, latch: bool = False) -> str:
        t = self.declare(topic, type_name)
        if latch:
            self._latch.add(topic)
        self._advertisers[topic] = self._advertisers.get(topic, 0) + 1
        return t

    def unadvertise(self, topic: str) -> None:
        """One publisher fewer; the in-process bus keeps a topic's type for its lifetime."""
        if self._advertisers.get(topic, 0) > 0:
            self._advertisers[topic] -= 1

    def publisher_count(self, topic: str) -> int:
        return self._advertisers.get(topic, 0)

    def type_of(self, topic: str) -> str | None:
        return self._types.get(topic)

    def topics(self) -> list[tuple[str, str]]:
        return sorted(self._types.items())

    def subscribe(self, topic: str, callback: Callback, type_name: str | None = None) -> Callable[[], None]:
        if type_name is not None:
            self.declare(topic, type_name)
        self._subs.setdefault(topic, []).append(callback)
        kept = self._latched.get(topic)
        if kept is not None:
            self._later(self._replay, topic, callback, kept)

        def unsubscribe() -> None:
            subs = self._subs.get(topic)
            if subs and callback in subs:
                subs.remove(callback)

        return unsubscribe

    def subscriber_count(self, topic: str) -> int:
        return len(self._subs.get(topic, ()))

    @staticmethod
    def _later(fn: Callable[..., None], *args: Any) -> None:
        """After the caller (the endpoint, setting up the subscription) is done: on the running loop."""
        try:
            asyncio.get_running_loop().call_soon(fn, *args)
        except RuntimeError:  # no loop (a test of the bus alone)
            fn(*args)

    def _replay(self, topic: str, callback: Callback, msg: dict[str, Any]) -> None:
        if callback in self._subs.get(topic, ()):
            try:
                callback(msg)
            except Exception:
                log.exception("subscriber of %s failed", topic)

    def publish(self, topic: str, msg: Any, type_name: str | None = None) -> dict[str, Any]:
        """Check ``msg`` against the topic's type and deliver it; returns the normalised message."""
        t = self.declare(topic, type_name) if type_name is not None else self._types.get(topic)
        if t is None:
            raise MessageError(f"cannot infer the type of {topic}: not yet advertised")
        checked = check_message(t, msg)
        self.published += 1
        if topic in self._latch:
            self._latched[topic] = checked
        for cb in tuple(self._subs.get(topic, ())):
            try:
                cb(checked)
            except Exception:
                log.exception("subscriber of %s failed", topic)
        for tap in self.taps:
            try:
                tap(topic, t, checked)
            except Exception:
                log.exception("topic monitor failed on %s", topic)
        return checked
