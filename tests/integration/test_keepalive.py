"""Dead links are found by WebSocket pings, from both ends, within a few seconds."""

import asyncio
import time

import aiohttp

from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import PING_INTERVAL_S, PING_TIMEOUT_S, RosLink

from ..support.backend import wait_for
from ..support.netfault import FaultProxy


def test_console_notices_a_silent_link_and_reconnects_when_it_returns(backend):
    proxy = FaultProxy(backend.bridge_port)
    link = RosLink("127.0.0.1", proxy.port)
    try:
        assert wait_for(lambda: link.state == CONNECTED, timeout=10)
        assert wait_for(lambda: link.telemetry.odom_count > 0)
        proxy.freeze()  # no FIN, no RST: only the keep-alive can tell
        frozen_at = time.monotonic()
        assert wait_for(lambda: link.state != CONNECTED, timeout=6)
        noticed = time.monotonic() - frozen_at
        assert noticed <= PING_INTERVAL_S + PING_TIMEOUT_S + 0.5, noticed
        assert link.send(0.3, 0.0) is False  # nothing is queued for later
        proxy.thaw()
        assert wait_for(lambda: link.state == CONNECTED, timeout=6)
        seen = link.telemetry.odom_count
        assert wait_for(lambda: link.telemetry.odom_count > seen + 3)  # subscribed again
    finally:
        link.close()
        proxy.close()


async def test_server_drops_a_client_that_stops_answering_pings(backend):
    async with aiohttp.ClientSession() as session:
        # autoping off: this client never answers the server's pings
        ws = await session.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}/", autoping=False)
        started = time.monotonic()
        pings = 0
        async for msg in ws:
            if msg.type == aiohttp.WSMsgType.PING:
                pings += 1
            elif msg.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.ERROR):
                break
        elapsed = time.monotonic() - started
        assert pings >= 1
        assert elapsed < 4.0, elapsed  # 2 s of silence, then 1 s for the pong
        assert ws.closed or ws.close_code is not None


async def test_server_keeps_a_quiet_client_that_answers_pings(backend):
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}/")  # answers pings
        try:  # (aiohttp restarts receive()'s own timeout at each ping it answers)
            msg = await asyncio.wait_for(ws.receive(), 5.0)
        except TimeoutError:
            msg = None
        assert msg is None and not ws.closed  # 5 s of silence, still connected
        await ws.send_str('{"op":"call_service","service":"/rosapi/topics","id":"t"}')
        reply = await ws.receive_json(timeout=2)
        assert reply["op"] == "service_response" and reply["result"] is True
        await ws.close()
