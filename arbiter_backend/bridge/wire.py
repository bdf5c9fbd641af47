"""The socket side of a client: the writer task, liveness pings, and the TCP options that keep a small
message from waiting (pacing and queue order are the client's, ``client.py``).

Liveness (``--ws-ping``): a client that has sent nothing for ``WS_PING_S`` is pinged (again
every ``WS_PING_S`` while it stays silent), and dropped when nothing at all, pong or frame, has
come from it for ``DEAD_AFTER`` pings' time (20 s by default), which frees its subscriptions and
advertisements. A client busy elsewhere that does not read its socket for 10 s is kept: its pong
waits behind the frames queued for it, and it answers once it reads again (the stock server does
not ping at all). The console finds a dead link on its side with its own pings (1 s, 2 s timeout).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket
import time

from aiohttp import web

from .client import Client

log = logging.getLogger(__name__)

WS_PING_S = 5.0  # ping a client silent this long (0/None: never), and again as often while it stays silent
DEAD_AFTER = 4  # ...and drop it once nothing has come from it for this many ping intervals


async def writer(client: Client) -> None:
    """Write what ``client`` has to send, reply first then topic by topic in turn, each write awaiting the
    socket's drain; big frames wait for its pacer. Ends when the socket goes or the client is kicked."""
    ws = client.ws
    try:
        clock = time.monotonic  # not loop.time(): uvloop's is per iteration, to the millisecond
        paced_until: float | None = None
        while True:
            if paced_until is None:
                await client.wakeup.wait()
            else:  # only big frames wait, for the pacer: until then, or until something else comes
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(client.wakeup.wait(), max(0.0, paced_until - clock()))
            client.wakeup.clear()
            while frames := client.next_turn(clock()):
                for frame in frames:
                    # each awaits the socket's drain past aiohttp's writer limit: a client gets
                    # frames as fast as it reads them, and the other clients never wait for it
                    started = clock()
                    if isinstance(frame, str):
                        await ws.send_str(frame)
                    else:
                        await ws.send_bytes(frame)
                    client.pacer.wrote(len(frame), started, clock())
            paced_until = client.pacer.next_at() if client.ring else None
            if client.kick is not None:
                code, reason = client.kick
                await ws.close(code=code, message=reason.encode("utf-8")[:120])
                return
    except (ConnectionError, RuntimeError, asyncio.CancelledError):
        pass  # the socket went away (ConnectionError: lost while waiting for it to drain)
    except Exception:
        log.exception("writer for client %d failed", client.id)


async def liveness(client: Client, transport: asyncio.Transport, interval: float) -> None:
    """Ping ``client`` while it is silent; cut the connection once it has been silent too long."""
    loop = asyncio.get_running_loop()
    pings: set[asyncio.Task[None]] = set()
    try:
        while not client.closed:
            idle = loop.time() - client.last_rx
            if idle >= interval * DEAD_AFTER:
                log.info("client %d: nothing received for %.1f s; dropping it", client.id, idle)
                transport.abort()  # no close handshake: the link is presumed dead
                return
            if idle >= interval:
                # a task: the ping may wait for the socket to drain; this loop must not
                ping = loop.create_task(_ping(client.ws))
                pings.add(ping)
                ping.add_done_callback(pings.discard)
            await asyncio.sleep(
                min(interval, interval * DEAD_AFTER - idle) if idle >= interval else interval - idle
            )
    finally:
        for ping in pings:
            ping.cancel()


async def _ping(ws: web.WebSocketResponse) -> None:
    with contextlib.suppress(ConnectionResetError, RuntimeError):
        await ws.ping()


def quick_ack(sock: socket.socket | None) -> None:
    """ACK what a client sent at once (Linux TCP_QUICKACK, which the kernel clears again, hence once
    per frame). A client with Nagle's algorithm on (a plain roslibpy script) holds its next small
    frame until the previous one is ACKed; with delayed ACKs here that stalled it ~40 ms at a time."""
    if sock is None or QUICKACK is None:
        return
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.IPPROTO_TCP, QUICKACK, 1)


QUICKACK = getattr(socket, "TCP_QUICKACK", None)
NOTSENT_LOWAT = getattr(socket, "TCP_NOTSENT_LOWAT", None)
UNSENT_BYTES = 64 * 1024


def limit_unsent(sock: socket.socket | None) -> None:
    """Keep at most ``UNSENT_BYTES`` not yet sent in the kernel's send buffer (TCP_NOTSENT_LOWAT, Linux
    and macOS): the rest of a big frame waits in the transport, where aiohttp's drain sees it, so what a
    slow client has not read is in its per-topic queues (dropped oldest first), not megabytes of socket
    buffer that a small message would wait behind."""
    if sock is None or NOTSENT_LOWAT is None:
        return
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.IPPROTO_TCP, NOTSENT_LOWAT, UNSENT_BYTES)
