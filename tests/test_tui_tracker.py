"""The latency poller against a real tracker that goes away and comes back."""

import socket

import pytest

from arbiter_tui.tracker_client import TrackerClient

from .conftest import start_backend


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def test_unreachable_then_recovered_then_down_again():
    port = free_port()
    client = TrackerClient(f"http://127.0.0.1:{port}", timeout=0.5)
    view = await client.poll()
    assert view.reachable is False and view.error == "ConnectError"
    b = start_backend("--api-port", str(port))
    # start_backend passes --api-port 0 first; the later flag wins
    try:
        assert b.api_port == port
        view = await client.poll()
        assert view.reachable is True and view.error is None
        assert view.stats["count"] == 0 and view.deploy_mode == "native"
    finally:
        b.stop()
    view = await client.poll()
    assert view.reachable is False
    assert view.stats["count"] == 0  # the last good answer stays on screen
    await client.aclose()


@pytest.mark.parametrize("body", [[], {"stats": 3}, {"stats": {}, "records": "x"}])
def test_bad_shapes_are_rejected(body):
    client = TrackerClient("http://127.0.0.1:9")
    with pytest.raises(ValueError):
        client.view.apply(body)
