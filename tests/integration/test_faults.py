"""Faults during a session, through the real app, link, poller and backend processes."""

import json
import subprocess
import sys
import time
from pathlib import Path

from arbiter_tui.analytics.files import FORMATS
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell.app import make_app
from arbiter_tui.shell.widgets.text import LINK_DOWN, StatusLine

from ..support.backend import free_port, get_json, start_backend
from ..support.points import make_point
from ..support.tui import RecordingLink, until


def text_of(app, selector: str) -> str:
    return str(app.screen.query_one(selector).render())


def live_settings(tmp_path, **kw) -> Settings:
    base = dict(
        handle_signals=False, export_dir=tmp_path, collection_rate=20.0, ui_rate=20.0, poll_period=0.2
    )
    return Settings(**{**base, **kw})


async def test_backend_killed_and_restarted_mid_drive(tmp_path):
    backend = start_backend()
    ports = ("--bridge-port", str(backend.bridge_port), "--api-port", str(backend.api_port))
    link = RosLink("127.0.0.1", backend.bridge_port)
    tracker = TrackerClient(backend.api)
    store = AnalyticsStore()
    # a long key timeout: the held key would still be "down" when the link returns
    app = make_app(live_settings(tmp_path, key_timeout=10.0, repeat_rate=20.0), link, tracker, store=store)
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=15)
            assert await until(pilot, lambda: link.telemetry.odom_count > 0)
            store.start_collection()
            await pilot.press("i")
            assert await until(pilot, lambda: link.telemetry.pose.x > 0.05, timeout=5)
            assert app.session.teleop.moving

            backend.proc.kill()
            killed = time.monotonic()
            assert await until(pilot, lambda: text_of(app, "#status").startswith("DISCONNECTED"), timeout=2)
            assert time.monotonic() - killed <= 1.0
            assert app.screen.query_one("#status", StatusLine).has_class("alarm")
            # the panel repaints on its own (the same UI tick, maybe a frame later): wait for it
            assert await until(pilot, lambda: LINK_DOWN.splitlines()[0] in text_of(app, "#robot"), timeout=2)
            # the held key is forgotten at the session's next control tick: no motion when the link returns
            assert await until(pilot, lambda: not app.session.teleop.moving, timeout=1)
            backend.proc.wait()
            await pilot.pause(1.0)  # an absence: a dead link adds no points and sends nothing
            kept = store.points()

            backend = start_backend(*ports)
            back = time.monotonic()
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=5)
            assert time.monotonic() - back <= 3.0
            odom = link.telemetry.odom_count
            assert await until(pilot, lambda: link.telemetry.odom_count > odom + 5)  # subscribed again
            await pilot.pause(1.0)  # an absence: nothing is sent by itself after the reconnect
            assert get_json(f"{backend.api}/api/health")["total_seen"] == 0  # nothing sent by itself
            assert link.telemetry.v == 0.0 and link.telemetry.pose.x == 0.0  # the new robot stood still
            assert LINK_DOWN.splitlines()[0] not in text_of(app, "#robot")

            await pilot.press("i")  # a new key press: advertised again, a zero first
            assert await until(pilot, lambda: get_json(f"{backend.api}/api/health")["total_seen"] >= 2)
            records = get_json(f"{backend.api}/api/latency")["records"]
            assert [r["linear_x"] for r in records[:2]] == [0.0, 0.5]
            assert await until(pilot, lambda: link.telemetry.reports >= 2)
            assert store.points()[: len(kept)] == kept  # every point collected is still there
            assert len(store) > len(kept)
    finally:
        link.close()
        backend.stop()


async def test_tracker_api_down_while_the_bridge_is_up(tmp_path):
    backend = start_backend()
    api_port = free_port()
    link = RosLink("127.0.0.1", backend.bridge_port)
    tracker = TrackerClient(f"http://127.0.0.1:{api_port}")
    app = make_app(live_settings(tmp_path), link, tracker, store=AnalyticsStore())
    api_only = None
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=15)
            await pilot.press("3")
            assert await until(pilot, lambda: "TRACKER UNREACHABLE" in text_of(app, "#lat-state"))
            assert "api UNREACHABLE" in text_of(app, "#status")
            # this console's own figures still work: the reports come over the bridge
            await pilot.press("1")
            await pilot.press("i")
            await pilot.press("3")
            assert await until(pilot, lambda: "rtt p50" in text_of(app, "#lat-client"))
            api_only = start_backend("--api-port", str(api_port), "--no-bridge", "--no-sim")
            assert await until(pilot, lambda: "tracker reachable" in text_of(app, "#lat-state"), timeout=5)
            status = text_of(app, "#status")
            assert "api" not in status and "deploy native" in status  # it answered: deploy mode shown
    finally:
        link.close()
        backend.stop()
        if api_only:
            api_only.stop()


async def test_bridge_down_while_the_tracker_api_is_up(tmp_path):
    api_only = start_backend("--no-bridge")
    bridge_port = free_port()
    link = RosLink("127.0.0.1", bridge_port)
    tracker = TrackerClient(api_only.api)
    app = make_app(live_settings(tmp_path), link, tracker, store=AnalyticsStore())
    bridge = None
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            assert await until(pilot, lambda: text_of(app, "#status").startswith("DISCONNECTED"), timeout=5)
            assert LINK_DOWN.splitlines()[0] in text_of(app, "#robot")
            await pilot.press("i")
            assert link.telemetry.meter.sent == 0  # nothing goes out, nothing is queued
            await pilot.press("3")
            assert await until(pilot, lambda: "tracker reachable" in text_of(app, "#lat-state"))
            assert "ROSBRIDGE LINK" in text_of(app, "#lat-client")
            bridge = start_backend("--bridge-port", str(bridge_port), "--api-port", "0")
            back = time.monotonic()
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=5)
            assert time.monotonic() - back <= 3.0
            assert await until(pilot, lambda: "ROSBRIDGE LINK" not in text_of(app, "#lat-client"))
            assert not app.screen.query_one("#status", StatusLine).has_class("alarm")
    finally:
        link.close()
        api_only.stop()
        if bridge:
            bridge.stop()


def filled_store(n: int = 500) -> AnalyticsStore:
    store = AnalyticsStore()
    store.start_collection()
    for i in range(n):
        store.record(make_point(i))
    return store


async def test_export_to_a_directory_that_cannot_be_written(tmp_path):
    store = filled_store()
    before = store.points()
    settings = Settings(handle_signals=False, live=False, export_dir="/proc/self", mode="sim")
    app = make_app(settings, RecordingLink(), None, store=store)
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("2")
        for key in ("c", "j", "m"):
            await pilot.press("ctrl+s", key)
            await pilot.pause(0.05)
            assert app.session.last_export.fmt == {"c": "csv", "j": "json", "m": "mcap"}[key]
            assert app.session.last_export.error is not None
            msg = [n.message for n in app._notifications][-1]
            assert msg.startswith("EXPORT FAILED") and "collected data kept" in msg, msg
        assert store.points() == before
        assert app.is_running  # still at the console


FULL_DISK = r"""
import json, resource, signal, sys
from pathlib import Path
sys.path.insert(0, sys.argv[2])
from tests.support.points import make_point
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.analytics.files import ExportError, export_store

signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # writes past the limit fail with EFBIG, as on a full disk
resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))
store = AnalyticsStore()
store.start_collection()
for i in range(2000):
    store.record(make_point(i))
out = {"before": len(store)}
for fmt in sys.argv[3:]:
    try:
        export_store(store, fmt, Path(sys.argv[1]))
        out[fmt] = "written"
    except ExportError as exc:
        out[fmt] = str(exc)
out["points"] = len(store)
print(json.dumps(out))
"""


def test_export_onto_a_full_disk_leaves_nothing_and_keeps_the_data(tmp_path):
    root = str(Path(__file__).resolve().parents[2])
    r = subprocess.run(
        [sys.executable, "-c", FULL_DISK, str(tmp_path), root, *FORMATS],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    for fmt in FORMATS:
        assert out[fmt].startswith("cannot write export to"), out
        assert "too large" in out[fmt].lower() or "space" in out[fmt].lower(), out[fmt]
    assert out["points"] == out["before"] == 1000  # the store's default size, untouched
    assert list(tmp_path.iterdir()) == []  # no partial file, no temporary left behind


async def test_the_status_line_names_why_odometry_does_not_come(tmp_path):
    """The robot's odometry topic carries another type: the server refuses the console's subscription,
    and the status line says so instead of only "no odometry"."""
    import roslibpy

    backend = start_backend()
    other = roslibpy.Ros("127.0.0.1", backend.bridge_port)
    other.run(timeout=10)
    wrong = roslibpy.Topic(other, "/wheel_odom", "std_msgs/String")
    wrong.advertise()  # a node that publishes it as a string
    ask = roslibpy.Service(other, "/rosapi/topic_type", "rosapi/TopicType")
    answer = ask.call(roslibpy.ServiceRequest({"topic": "/wheel_odom"}), timeout=5)
    assert answer["type"] == "std_msgs/msg/String"
    link = RosLink("127.0.0.1", backend.bridge_port, odom_topic="/wheel_odom")
    app = make_app(live_settings(tmp_path), link, TrackerClient(backend.api))
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=15)
            assert await until(pilot, lambda: link.odometry_problem is not None, timeout=5)
            assert "std_msgs/msg/String" in link.odometry_problem
            said = "no odometry on /wheel_odom: topic /wheel_odom has type std_msgs/msg/String"
            assert await until(pilot, lambda: said in text_of(app, "#status"), timeout=5)
    finally:
        link.close()
        other.close()
        backend.stop()
