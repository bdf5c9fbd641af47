"""An rclpy future as an asyncio one: its result crosses from the executor's thread to the event loop."""

from __future__ import annotations

import asyncio
import contextlib
from typing import Any


def on_loop(loop: asyncio.AbstractEventLoop, future: Any) -> asyncio.Future[Any]:
    """An asyncio future on ``loop`` that settles as the rclpy ``future`` does (its result or exception);
    a loop already closed when it settles is left alone."""
    answer: asyncio.Future[Any] = loop.create_future()

    def settle(done: Any) -> None:  # the executor's thread (or here, when already done)
        def set_answer() -> None:
            if answer.done():
                return
            if done.exception() is not None:
                answer.set_exception(done.exception())
            else:
                answer.set_result(done.result())

        with contextlib.suppress(RuntimeError):
            loop.call_soon_threadsafe(set_answer)

    future.add_done_callback(settle)
    return answer
