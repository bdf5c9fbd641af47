"""The latency poller against a real tracker that goes away and comes back."""

import asyncio
import json
import time

import aiohttp
import httpx
import pytest

from arbiter_core import envelope
from arbiter_tui.latency.tracker_client import TrackerClient

from ..support.backend import free_port, start_backend
from ..support.tui import still_app, tracker_said


async def test_unreachable_then_recovered_then_down_again():
    port = free_port()
    client = TrackerClient(f"http://127.0.0.1:{port}", timeout=0.5)
    view = await client.poll()
    assert view.reachable is False and view.error == "connection refused"
    b = start_backend("--api-port", str(port))
    # start_backend passes --api-port 0 first; the later flag wins
    try:
        assert b.api_port == port
        view = await client.poll()
        assert view.reachable is True and view.error is None
        assert view.stats.count == 0 and view.deploy_mode == "native"
    finally:
        b.stop()
    view = await client.poll()
    assert view.reachable is False
    assert view.stats.count == 0  # the last good answer stays on screen
    await client.aclose()


@pytest.mark.parametrize("body", [[], {"stats": 3}, {"stats": {}, "records": "x"}])
def test_bad_shapes_are_rejected(body):
    client = TrackerClient("http://127.0.0.1:9")
    with pytest.raises(ValueError):
        client.view.apply(body)


async def test_stale_and_rejected_commands_are_shown_on_the_latency_screen():
    """Commands the tracker drops as too old are why a robot does not move: the screen says so."""
    b = start_backend()
    try:
        async with aiohttp.ClientSession() as session:
            ws = await session.ws_connect(f"ws://127.0.0.1:{b.bridge_port}/")
            await ws.send_str('{"op":"advertise","topic":"/stamped_cmd_vel","type":"std_msgs/String"}')
            old = lambda: time.time_ns() - 2_000_000_000  # noqa: E731
            for i, data in enumerate([envelope.build(0.2, 0, seq=1, clock_ns=old)] * 3 + ["{bad"] * 2):
                frame = {"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": data}, "id": i}
                await ws.send_str(json.dumps(frame))
            await ws.close()
        tracker = TrackerClient(b.api)
        for _ in range(50):
            view = await tracker.poll()
            if view.stale == 3 and view.rejected == 2:
                break
            await asyncio.sleep(0.05)
        assert (view.stale, view.rejected, view.max_command_age_ms) == (3, 2, 300.0)
        body = httpx.get(f"{b.api}/api/latency").json()
        app = still_app()
        app.tracker.view.apply(body)
        tracker_said(app)
        async with app.run_test(size=(100, 30)) as pilot:
            await pilot.press("3")
            await pilot.pause(0.1)
            text = str(app.screen.query_one("#lat-state").render())
            assert "3 STALE > 300 ms, not forwarded" in text and "2 rejected" in text
        await tracker.aclose()
    finally:
        b.stop()


async def test_both_hosts_time_sync_is_read_with_the_first_poll():
    """The robot's from /api/health's time_sync, ours from the same probes; never an error."""
    b = start_backend()
    client = TrackerClient(b.api)
    try:
        view = await client.poll()
        assert view.reachable
        assert view.robot_sync is not None and view.local_sync is not None
        assert view.robot_sync.source in ("chrony", "timesyncd", "adjtimex", "unknown")
        # same host, same kernel: the two say the same
        assert (view.robot_sync.source, view.robot_sync.synchronised) == (
            view.local_sync.source,
            view.local_sync.synchronised,
        )
    finally:
        await client.aclose()
        b.stop()
