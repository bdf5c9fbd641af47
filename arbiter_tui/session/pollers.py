"""One polling helper for the tracker's HTTP API: the next poll is scheduled when the last one finished
(a slow answer never piles polls up), and each answer is handed on as a frozen value (no Textual)."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable
from typing import TypeVar

T = TypeVar("T")


async def poll_forever(
    poll: Callable[[], Awaitable[T]],
    period_s: float | Callable[[], float],
    deliver: Callable[[T], None],
    wanted: Callable[[], bool] = lambda: True,
    clock: Callable[[], float] = time.monotonic,
) -> None:
    """``poll()`` every ``period_s`` (from the start of one to the start of the next, or at once after a
    poll that took longer; a callable: asked each time), while ``wanted()``; each answer goes to
    ``deliver``. Runs until cancelled."""
    while True:
        started = clock()
        if wanted():
            deliver(await poll())
        period = period_s() if callable(period_s) else period_s
        await asyncio.sleep(max(0.0, period - (clock() - started)))
