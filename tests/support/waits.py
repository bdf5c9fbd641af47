"""Waiting on a condition instead of for a fixed time: fast when things are fast, patient when the
machine is loaded. A fixed sleep remains only where a test proves that nothing happens for a while
(no second zero, a robot that stays still) or paces what it sends."""

import asyncio
import time
from collections.abc import Awaitable, Callable
from typing import TypeVar

T = TypeVar("T")


def wait_for(predicate: Callable[[], object], timeout: float = 5.0, interval: float = 0.02) -> bool:
    """Poll ``predicate`` from a plain thread until it holds (True) or ``timeout`` passes (its last value)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(interval)
    return bool(predicate())


async def async_until(predicate: Callable[[], object], timeout: float = 5.0, interval: float = 0.01) -> bool:
    """The same inside an event loop: the loop keeps serving (servers in the test's own loop) meanwhile."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        await asyncio.sleep(interval)
    return bool(predicate())


async def async_poll(
    probe: Callable[[], Awaitable[T]],
    done: Callable[[T], object],
    timeout: float = 10.0,
    interval: float = 0.1,
) -> T:
    """Ask ``probe()`` (a request to a server) until ``done(answer)`` holds or ``timeout`` passes; the last
    answer either way, for the test to assert on (and show when it fails)."""
    deadline = time.monotonic() + timeout
    answer = await probe()
    while not done(answer) and time.monotonic() < deadline:
        await asyncio.sleep(interval)
        answer = await probe()
    return answer
