"""A loopback TCP proxy that delays each direction by a known amount: injected ground truth for the
latency figures (tests/integration/test_groundtruth.py, bench/groundtruth.py).

asyncio, on its own loop in a daemon thread. Every chunk read is released ``delay (+ jitter)`` after it
arrived, in order (a chunk never overtakes the one before it, as on a TCP stream); jitter is uniform
``[0, jitter]`` or half-normal ``|N(0, jitter)|``, on both directions or the forward one only.
``forward`` is client to upstream (the console's commands), ``back`` upstream to client (the reports).
``stall(s)`` holds every byte for ``s`` seconds (a link that hangs, then delivers); ``blackhole(s)`` drops
what arrives for ``s`` seconds and then closes the connections (a link that dies: the stream cannot carry
on with a hole).

Precision: the event loop's timers round up to the millisecond (epoll), so the last 1.5 ms of each wait
is a busy wait that yields to the loop (``sleep(0)``: the other direction keeps being served, its
arrival times stay exact): the injected delay is what the bytes see, to within ~0.1 ms on an idle
machine. A measurement at 0/0 gives the rest of the path (the "base").
"""

from __future__ import annotations

import asyncio
import contextlib
import random
import socket
import threading
import time
from dataclasses import dataclass

SPIN_S = 0.0015


@dataclass
class Delays:
    forward_ms: float = 0.0
    back_ms: float = 0.0
    jitter_ms: float = 0.0  # each chunk: + uniform [0, jitter] (never reordered)
    jitter_kind: str = "uniform"  # or "halfnormal": + |N(0, jitter)|
    jitter_back: bool = True  # False: only the forward direction is jittered


class DelayProxy:
    def __init__(self, upstream_port: int, delays: Delays | None = None, seed: int = 0) -> None:
        self.upstream_port = upstream_port
        self.delays = delays or Delays()
        self._rnd = random.Random(seed)
        self._hold_until = 0.0  # monotonic: stalled until then
        self._drop_until = 0.0  # monotonic: dropping until then
        self._writers: set[asyncio.StreamWriter] = set()
        self.chunks = [0, 0]  # forwarded chunks: forward, back
        self.jitter_drawn: tuple[list[float], list[float]] = ([], [])  # ms, per direction (the truth)
        self._loop = asyncio.new_event_loop()
        ready = threading.Event()
        self._thread = threading.Thread(target=self._run, args=(ready,), daemon=True)
        self._thread.start()
        ready.wait(5)
        self.port: int = self._port

    # -- control (any thread) --------------------------------------------------------------------
    def set(self, forward_ms: float, back_ms: float, jitter_ms: float = 0.0, jitter_kind: str = "uniform",
            jitter_back: bool = True) -> None:  # fmt: skip
        self.delays = Delays(forward_ms, back_ms, jitter_ms, jitter_kind, jitter_back)

    def stall(self, seconds: float) -> None:
        self._hold_until = time.monotonic() + seconds

    def blackhole(self, seconds: float) -> None:
        self._drop_until = time.monotonic() + seconds
        self._loop.call_soon_threadsafe(self._loop.call_later, seconds, self._close_all)

    def close(self) -> None:
        if self._loop.is_closed():
            return
        fut = asyncio.run_coroutine_threadsafe(self._shutdown(), self._loop)
        with contextlib.suppress(Exception):
            fut.result(5)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(5)

    def __enter__(self) -> DelayProxy:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the loop -------------------------------------------------------------------------------------
    def _run(self, ready: threading.Event) -> None:
        asyncio.set_event_loop(self._loop)
        self._server = self._loop.run_until_complete(asyncio.start_server(self._accept, "127.0.0.1", 0))
        self._port = self._server.sockets[0].getsockname()[1]
        ready.set()
        self._loop.run_forever()
        self._loop.close()

    async def _shutdown(self) -> None:
        self._server.close()
        self._close_all()
        tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
        if tasks:  # closed transports end their pipes (EOF); what still waits is cancelled
            _done, pending = await asyncio.wait(tasks, timeout=2)
            for t in pending:
                t.cancel()

    def _close_all(self) -> None:
        for w in list(self._writers):
            with contextlib.suppress(Exception):
                w.close()
        self._writers.clear()

    async def _accept(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            up_reader, up_writer = await asyncio.open_connection("127.0.0.1", self.upstream_port)
        except OSError:
            writer.close()
            return
        self._writers |= {writer, up_writer}
        for w in (writer, up_writer):  # the proxy adds no Nagle delay of its own
            sock = w.get_extra_info("socket")
            if sock is not None:
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        with contextlib.suppress(asyncio.CancelledError):
            await asyncio.gather(
                self._pipe(reader, up_writer, 0), self._pipe(up_reader, writer, 1), return_exceptions=True
            )
        for w in (writer, up_writer):
            self._writers.discard(w)
            with contextlib.suppress(Exception):
                w.close()

    async def _pipe(self, src: asyncio.StreamReader, dst: asyncio.StreamWriter, direction: int) -> None:
        queue: asyncio.Queue[tuple[float, bytes] | None] = asyncio.Queue()
        sender = asyncio.ensure_future(self._send(queue, dst, direction))
        last = 0.0
        try:
            while True:
                data = await src.read(65536)
                now = time.monotonic()
                if not data:
                    break
                if now < self._drop_until:
                    continue
                d = self.delays
                delay = (d.forward_ms if direction == 0 else d.back_ms) / 1000.0
                if d.jitter_ms and (direction == 0 or d.jitter_back):
                    if d.jitter_kind == "halfnormal":
                        j = abs(self._rnd.gauss(0.0, d.jitter_ms))
                    else:
                        j = self._rnd.uniform(0.0, d.jitter_ms)
                    self.jitter_drawn[direction].append(j)
                    delay += j / 1000.0
                last = max(last, now + delay)  # in order, as a stream
                queue.put_nowait((last, data))
        finally:
            queue.put_nowait(None)
            await sender

    async def _send(self, queue: asyncio.Queue, dst: asyncio.StreamWriter, direction: int) -> None:
        while True:
            item = await queue.get()
            if item is None:
                with contextlib.suppress(Exception):
                    dst.close()
                return
            due, data = item
            due = max(due, self._hold_until)
            wait = due - time.monotonic()
            if wait > SPIN_S:
                await asyncio.sleep(wait - SPIN_S)
            while time.monotonic() < due:  # the last ms precisely: epoll timeouts round up to whole ms
                await asyncio.sleep(0)
            if time.monotonic() < self._drop_until:
                continue
            try:
                dst.write(data)
                await dst.drain()
            except (ConnectionError, RuntimeError):
                return
            self.chunks[direction] += 1
