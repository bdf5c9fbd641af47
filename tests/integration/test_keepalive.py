"""Dead links are found by WebSocket pings, from both ends; a busy client that stops reading is kept."""

import asyncio
import json
import time

import aiohttp
import pytest

from arbiter_backend.bridge import DEAD_AFTER, WS_PING_S
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import PING_INTERVAL_S, PING_TIMEOUT_S, RosLink

from ..support.backend import start_backend, wait_for
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


@pytest.fixture
def quick_pings():
    b = start_backend("--ws-ping", "0.5", "--no-sim")
    yield b
    b.stop()


async def test_server_drops_a_client_that_stops_answering_pings(quick_pings):
    async with aiohttp.ClientSession() as session:
        # autoping off: this client never answers the server's pings
        ws = await session.ws_connect(f"ws://127.0.0.1:{quick_pings.bridge_port}/", autoping=False)
        started = time.monotonic()
        pings = 0
        async for msg in ws:
            if msg.type == aiohttp.WSMsgType.PING:
                pings += 1
            elif msg.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.ERROR):
                break
        elapsed = time.monotonic() - started
        assert pings >= 2  # pinged every 0.5 s while silent
        assert 0.5 * DEAD_AFTER - 0.1 <= elapsed < 0.5 * DEAD_AFTER + 1.5, elapsed
        assert ws.closed or ws.close_code is not None


async def test_pings_off_never_drops_a_silent_client():
    b = start_backend("--ws-ping", "0", "--no-sim")
    try:
        async with aiohttp.ClientSession() as session:
            ws = await session.ws_connect(f"ws://127.0.0.1:{b.bridge_port}/", autoping=False)
            with pytest.raises(asyncio.TimeoutError):
                msg = await ws.receive(timeout=2.5)  # nothing at all: no ping, no close
                raise AssertionError(msg)
            await ws.send_str('{"op":"call_service","service":"/nope","id":"q"}')
            assert json.loads((await ws.receive(timeout=5)).data)["id"] == "q"
    finally:
        b.stop()


@pytest.mark.slow
async def test_a_busy_client_that_does_not_read_for_ten_seconds_is_kept(backend):
    """The issue's case, with the default --ws-ping: the stock server keeps such a client; so do we."""
    assert WS_PING_S * (DEAD_AFTER - 1) > 10
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}/")
        await ws.send_str('{"op":"subscribe","topic":"/odom"}')  # 50 Hz from the simulator
        started = time.monotonic()
        await asyncio.sleep(11)  # busy elsewhere: not a byte read, no pong sent
        assert time.monotonic() - started >= 11
        frame = json.loads((await ws.receive(timeout=5)).data)
        assert frame["op"] == "publish" and frame["topic"] == "/odom"
        await ws.send_str('{"op":"call_service","service":"/nope","id":"after"}')
        while (reply := json.loads((await ws.receive(timeout=5)).data))["op"] != "service_response":
            pass
        assert reply["id"] == "after" and not ws.closed


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
