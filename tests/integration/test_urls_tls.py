"""URLs done right, through real servers: wss:// is TLS with a verified certificate, the path is kept,
and a token never travels in clear to another machine."""

import socket
import ssl
import threading

import httpx
import pytest
from aiohttp import web

from arbiter_backend.bridge import RosbridgeEndpoint
from arbiter_backend.bus import TopicBus
from arbiter_core.failures import TLS_HINT, TOKEN_HINT
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.cli import main as tui_main
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import AUTH_RETRY_S, RosLink

from ..support.backend import start_backend
from ..support.certs import self_signed
from ..support.servers import serve
from ..support.waits import async_until


@pytest.fixture
def tls_backend(tmp_path):
    cert, key = self_signed(tmp_path)
    b = start_backend("--tls-cert", str(cert), "--tls-key", str(key))
    yield b, cert
    b.stop()


async def test_wss_with_a_private_ca_drives_the_robot_and_https_polls_the_tracker(tls_backend):
    backend, cert = tls_backend
    link = RosLink("localhost", backend.bridge_port, secure=True, ca_file=cert)
    api = f"https://localhost:{backend.api_port}"
    tracker = TrackerClient(api, ca_file=cert)
    try:
        assert link.url.startswith("wss://localhost:")
        assert await async_until(lambda: link.state == CONNECTED, timeout=10)
        for _ in range(5):
            assert link.send(0.2, 0.0)
        assert await async_until(lambda: link.telemetry.reports >= 5, timeout=5)  # reports came back over TLS
        view = await tracker.poll()
        assert view.reachable and view.stats.count == 5, view.error
        with pytest.raises(httpx.HTTPError):  # plain http to the TLS port is not answered as http
            httpx.get(f"http://localhost:{backend.api_port}/api/health", timeout=2)
    finally:
        link.close()
        await tracker.aclose()


async def test_wss_to_an_untrusted_certificate_never_connects(tls_backend):
    backend, _cert = tls_backend
    link = RosLink("localhost", backend.bridge_port, secure=True)  # the system's CAs do not know it
    try:
        assert not await async_until(lambda: link.state == CONNECTED, timeout=2.5)
        assert link.error == TLS_HINT
        trusted = ssl.create_default_context(cafile=str(_cert))
        health = httpx.get(f"https://localhost:{backend.api_port}/api/health", verify=trusted).json()
        assert health["total_seen"] == 0  # nothing reached the tracker
    finally:
        link.close()


def test_wss_opens_with_a_tls_hello_and_never_sends_the_token_in_clear():
    token = "s3cret-token-0123456789"
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        server.settimeout(10)
        port = server.getsockname()[1]
        got: list[bytes] = []

        def accept():
            conn, _ = server.accept()
            with conn:
                conn.settimeout(3)
                try:
                    got.append(conn.recv(4096))
                except OSError:
                    got.append(b"")

        t = threading.Thread(target=accept, daemon=True)
        t.start()
        link = RosLink("localhost", port, secure=True, token=token)
        try:
            t.join(10)
        finally:
            link.close()
    assert got and got[0][:1] == b"\x16"  # a TLS handshake record (ClientHello)
    assert b"GET" not in got[0] and token.encode() not in got[0]


async def test_the_url_path_is_kept():
    endpoint = RosbridgeEndpoint(TopicBus())
    app = web.Application()
    app.router.add_get("/rosbridge/ws", endpoint.handle)  # a server mounted below a path
    runner, port = await serve(app)
    good = RosLink("127.0.0.1", port, path="/rosbridge/ws")
    wrong = RosLink("127.0.0.1", port)  # "/": 404
    try:
        assert good.url == f"ws://127.0.0.1:{port}/rosbridge/ws"
        assert await async_until(lambda: good.state == CONNECTED, timeout=10)
        assert await async_until(lambda: (wrong.error or "").startswith("HTTP 404: wrong path"), timeout=5)
        assert wrong.state != CONNECTED
    finally:
        good.close()
        wrong.close()
        await endpoint.close_all()
        await runner.cleanup()


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--rosbridge", "ws://10.9.8.7:9090"], "never sent in clear"),
        (["--rosbridge", "ws://127.0.0.1:9090", "--tracker", "http://10.9.8.7:8085"], "use https://"),
        (["--rosbridge", "ftp://robot"], "must start with ws:// or wss://"),
        (["--rosbridge", "wss://robot:70000"], "out of range"),
        (["--tracker", "http://:8085"], "no host"),
        (["--sim", "--rosbridge", "ws://robot"], "not with --sim"),
        (["--rosbridge", "wss://robot", "--ca-file", "/definitely/missing.pem"], "no such file"),
    ],
)
def test_bad_urls_and_the_token_rule_stop_before_anything_starts(args, words, capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("ARBITER_TOKEN", "t" * 24)
    monkeypatch.chdir(tmp_path)
    try:
        code = tui_main([*args, "--log-file", str(tmp_path / "log")])
    except SystemExit as exc:  # a value argparse's own type check refuses (arbiter_core.cliargs)
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err


async def test_connection_errors_say_what_failed_on_screen(tmp_path):
    from arbiter_tui.session.settings import Settings
    from arbiter_tui.shell.app import make_app

    from ..support.backend import free_port
    from ..support.tui import until

    refused = RosLink("127.0.0.1", free_port())
    unknown = RosLink("no-such-robot.invalid", 9090)
    settings = Settings(handle_signals=False, export_dir=tmp_path, mode="connect", rosbridge_url=refused.url)
    app = make_app(
        settings, refused, TrackerClient(f"http://127.0.0.1:{free_port()}"), store=AnalyticsStore()
    )
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            status = lambda: app.screen.query_one("#status").render().plain  # noqa: E731
            assert await until(pilot, lambda: "connection refused" in status(), timeout=5)
            assert status().startswith(f"DISCONNECTED · connect {refused.url}")
            await pilot.press("3")
            assert await until(
                pilot, lambda: "connection refused" in app.screen.query_one("#lat-state").render().plain
            )
            assert (
                "TRACKER UNREACHABLE at http://127.0.0.1:"
                in app.screen.query_one("#lat-state").render().plain
            )
            assert await async_until(
                lambda: (unknown.error or "").startswith("DNS lookup failed"), timeout=10
            )
    finally:
        refused.close()
        unknown.close()


async def test_a_rejected_token_is_said_and_retried_slowly(monkeypatch):
    monkeypatch.setenv("ARBITER_TOKEN", "a-token-of-twenty-four-chars")
    backend = start_backend()  # wants the token
    monkeypatch.delenv("ARBITER_TOKEN")
    link = RosLink("127.0.0.1", backend.bridge_port)  # presents none
    try:
        assert await async_until(lambda: (link.error or "").startswith(TOKEN_HINT), timeout=10)
        assert link.ros.factory.maxDelay == AUTH_RETRY_S
    finally:
        link.close()
        backend.stop()
