"""Loopback by default; a token for anything else, through each of the ways a client can send it."""

import json
import subprocess
import sys
import time

import aiohttp
import httpx
import pytest

from arbiter_core import auth, envelope
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink

from ..support.backend import start_backend, wait_for

TOKEN = "s3cret-token-for-the-tests-0123"
PUBLISH = json.dumps(
    {"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": envelope.build(0.1, 0.0, seq=1)}}
)
ADVERTISE = '{"op":"advertise","topic":"/stamped_cmd_vel","type":"std_msgs/String"}'


@pytest.fixture(scope="module")
def secured():
    b = start_backend(env={auth.TOKEN_ENV: TOKEN})
    yield b
    b.stop()


def total_seen(b) -> int:
    r = httpx.get(f"{b.api}/api/health", headers={"Authorization": f"Bearer {TOKEN}"}, timeout=5)
    return r.json()["total_seen"]


def test_http_api_needs_the_bearer_token(secured):
    for headers in ({}, {"Authorization": "Bearer wrong-token-wrong-token"}, {"Authorization": TOKEN}):
        r = httpx.get(f"{secured.api}/api/latency", headers=headers, timeout=5)
        assert r.status_code == 401 and r.headers["WWW-Authenticate"].startswith("Bearer")
        assert r.json()["status"] == 401 and "bearer" in r.json()["error"]
    r = httpx.get(f"{secured.api}/api/latency", headers={"Authorization": f"Bearer {TOKEN}"}, timeout=5)
    assert r.status_code == 200 and r.json()["stats"]["count"] == 0
    # /api/topics: the same rule
    assert httpx.get(f"{secured.api}/api/topics", timeout=5).status_code == 401
    r = httpx.get(f"{secured.api}/api/topics", headers={"Authorization": f"Bearer {TOKEN}"}, timeout=5)
    assert r.status_code == 200 and "/odom" in {t["name"] for t in r.json()["topics"]}


async def test_websocket_without_a_token_is_refused_and_nothing_reaches_the_robot(secured):
    url = f"ws://127.0.0.1:{secured.bridge_port}/"
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(url)
        await ws.send_str(ADVERTISE)
        await ws.send_str(PUBLISH)
        status = await ws.receive_json(timeout=3)
        assert status["op"] == "status" and status["level"] == "error"
        assert "authentication required" in status["msg"]
        closing = await ws.receive(timeout=3)
        assert closing.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED)
        assert ws.close_code == 1008
        # a wrong token in the query or the header: refused at the handshake
        for kwargs in ({"params": {"token": "x" * 20}}, {"headers": {"Authorization": "Bearer " + "y" * 20}}):
            with pytest.raises(aiohttp.WSServerHandshakeError) as err:
                await session.ws_connect(url, **kwargs)
            assert err.value.status == 401
        # a wrong token in the auth op
        ws = await session.ws_connect(url)
        await ws.send_str(json.dumps({"op": "auth", "mac": "z" * 20}))
        await ws.send_str(ADVERTISE)
        status = await ws.receive_json(timeout=3)
        assert "wrong token" in status["msg"]
        await ws.receive(timeout=3)
        assert ws.close_code == 1008
    time.sleep(0.2)  # an absence: nothing may be recorded in the meantime
    assert total_seen(secured) == 0


async def test_auth_op_and_query_token_let_commands_through(secured):
    url = f"ws://127.0.0.1:{secured.bridge_port}/"
    before = total_seen(secured)
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(url)
        await ws.send_str(json.dumps({"op": "auth", "mac": TOKEN, "client": "", "dest": "", "rand": ""}))
        await ws.send_str(ADVERTISE)
        await ws.send_str(PUBLISH)
        ws2 = await session.ws_connect(url, params={"token": TOKEN})
        await ws2.send_str(ADVERTISE)
        await ws2.send_str(PUBLISH)
        assert wait_for(lambda: total_seen(secured) == before + 2, timeout=3)
        await ws.close()
        await ws2.close()


async def test_a_silent_unauthenticated_client_is_closed_after_the_deadline(secured):
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(f"ws://127.0.0.1:{secured.bridge_port}/")
        started = time.monotonic()
        status = await ws.receive_json(timeout=auth.AUTH_DEADLINE_S + 3)
        assert "within" in status["msg"]
        await ws.receive(timeout=3)
        assert ws.close_code == 1008
        assert auth.AUTH_DEADLINE_S - 0.5 < time.monotonic() - started < auth.AUTH_DEADLINE_S + 2


async def test_console_link_and_poller_send_the_token(secured):
    link = RosLink("127.0.0.1", secured.bridge_port, token=TOKEN)
    tracker = TrackerClient(secured.api, token=TOKEN)
    try:
        assert wait_for(lambda: link.state == CONNECTED, timeout=10)
        assert wait_for(lambda: link.telemetry.odom_count > 0)  # subscriptions went through
        before = total_seen(secured)
        assert link.send(0.1, 0.0)
        assert wait_for(lambda: link.telemetry.reports >= 1)
        assert total_seen(secured) == before + 1
        view = await tracker.poll()
        assert view.reachable and view.stats.count >= 1
        bare = TrackerClient(secured.api)
        assert (await bare.poll()).error.startswith("token rejected") and "HTTP 401" in bare.view.error
        await bare.aclose()
    finally:
        await tracker.aclose()
        link.close()


def run_backend(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "arbiter_backend.cli", "--bridge-port", "0", "--api-port", "0", *args],
        capture_output=True,
        text=True,
        timeout=20,
        env={"PATH": "/usr/bin:/bin", **(env or {})},
    )


@pytest.mark.parametrize(
    ("args", "env", "message"),
    [
        (["--host", "0.0.0.0"], {}, "without --allow-remote; use an SSH tunnel"),
        (["--host", "::"], {}, "without --allow-remote"),
        (["--host", "0.0.0.0", "--allow-remote"], {}, "--allow-remote needs a token"),
        (["--host", "0.0.0.0", "--allow-remote"], {auth.TOKEN_ENV: "short"}, "at least 16"),
        (["--token-file", "/nonexistent/token"], {}, "cannot read --token-file"),
    ],
)
def test_exposure_without_allow_remote_and_token_is_refused(args, env, message):
    r = run_backend(*args, env=env)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and lines[0].startswith("arbiter-backend: ")


def test_allow_remote_with_a_token_file_binds_all_addresses_and_still_checks(tmp_path):
    token_file = tmp_path / "token"
    token_file.write_text(TOKEN + "\n")
    b = start_backend("--host", "0.0.0.0", "--allow-remote", "--token-file", str(token_file))
    try:
        bare = httpx.get(f"{b.api}/api/health", timeout=5)
        assert bare.status_code == 401
        ok = httpx.get(f"{b.api}/api/health", headers={"Authorization": f"Bearer {TOKEN}"}, timeout=5)
        assert ok.status_code == 200
    finally:
        b.stop()


@pytest.mark.parametrize(
    ("host", "loopback"),
    [
        ("127.0.0.1", True),
        ("127.1.2.3", True),
        ("::1", True),
        ("localhost", True),
        ("0.0.0.0", False),
        ("192.168.1.5", False),
        ("robot.local", False),
    ],
)
def test_is_loopback(host, loopback):
    assert auth.is_loopback(host) is loopback
