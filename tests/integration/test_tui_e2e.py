"""The app end to end against the real bundled backend: roslibpy over WebSocket, httpx over HTTP."""

import asyncio
import time

from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED, DISCONNECTED, RECONNECTING
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell.app import make_app

from ..support.backend import get_json, start_backend
from ..support.tui import until


async def test_keys_to_tracker_records_to_odometry_to_data_points(tmp_path):
    backend = start_backend()
    link = RosLink("127.0.0.1", backend.bridge_port)
    tracker = TrackerClient(backend.api)
    store = AnalyticsStore()
    settings = Settings(handle_signals=False, export_dir=tmp_path, collection_rate=20.0)
    app = make_app(settings, link, tracker, store=store)
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=15)
            assert await until(pilot, lambda: link.telemetry.odom_count > 0)
            store.start_collection()
            for _ in range(15):  # hold "i" with auto-repeat
                await pilot.press("i")
                await pilot.pause(0.05)
            assert await until(pilot, lambda: link.telemetry.pose.x > 0.1)
            body = get_json(f"{backend.api}/api/latency?limit=1000")
            assert body["stats"]["count"] >= 15
            assert all(r["linear_x"] in (0.5, 0.0) for r in body["records"])
            assert [r["seq"] for r in body["records"]] == sorted(r["seq"] for r in body["records"])
            assert await until(pilot, lambda: link.telemetry.reports >= 15)
            # the robot stops by itself after the key timeout
            assert await until(pilot, lambda: link.telemetry.v == 0.0, timeout=3)
            assert get_json(f"{backend.api}/api/latency?limit=1")["records"][-1]["linear_x"] == 0.0
            # data points carry the pose, the command and the latency
            pts = store.points()
            assert len(pts) > 5
            assert any(p.linearVel == 0.5 for p in pts)
            assert max(p.x for p in pts) > 0.1
            assert any(p.latencyMs is not None for p in pts)
            # the latency screen shows the tracker's figures
            await pilot.press("3")
            assert await until(pilot, lambda: tracker.view.reachable and tracker.view.stats.count >= 15)
            await pilot.pause(0.3)
            assert "tracker reachable" in str(app.screen.query_one("#lat-state").render())

            # backend killed: DISCONNECTED, nothing sent; it returns: reconnected, zero first
            await pilot.press("1")
            backend.proc.kill()
            backend.proc.wait()
            assert await until(pilot, lambda: link.state in (DISCONNECTED, RECONNECTING), timeout=2)
            assert link.send(0.3, 0.0) is False
            assert await until(pilot, lambda: tracker.view.reachable is False, timeout=3)
            backend = start_backend(
                "--bridge-port", str(backend.bridge_port), "--api-port", str(backend.api_port)
            )
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=6)
            await asyncio.sleep(0.3)
            assert link.send(0.2, 0.0) is True
            records = []
            deadline = time.monotonic() + 3
            while len(records) < 2 and time.monotonic() < deadline:
                records = get_json(f"{backend.api}/api/latency")["records"]
                await pilot.pause(0.05)
            assert [r["linear_x"] for r in records[:2]] == [0.0, 0.2]  # a zero goes first after reconnect
            assert len(store) > 5  # nothing collected was lost
    finally:
        link.close()
        backend.stop()


async def test_topics_screen_polls_the_backend_and_echoes_the_selected_topic(tmp_path):
    """Screen 4 against the real backend: the table fills from GET /api/topics, the simulator's odometry
    is ok at its rate, and the selected topic's latest message arrives through rosbridge (throttled).
    Leaving the screen stops both the polls and the echo."""
    from arbiter_tui.shell.widgets.topics import TopicDetail, TopicsList

    backend = start_backend("--topics-window", "2")
    link = RosLink("127.0.0.1", backend.bridge_port)
    tracker = TrackerClient(backend.api)
    settings = Settings(handle_signals=False, export_dir=tmp_path)
    app = make_app(settings, link, tracker)
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=15)
            await pilot.press("4")
            table = app.screen.query_one(TopicsList)

            def odom_ok() -> bool:  # as the table on screen shows it
                odom = next((t for t in table.state.topics if t.name == "/odom"), None)
                return odom is not None and odom.state == "ok" and (odom.rate_hz or 0) > 40

            assert await until(pilot, odom_ok, timeout=15)
            assert "/stamped_cmd_vel" in {t.name for t in table.rows()}
            await pilot.press("slash", *"odom", "enter")
            assert await until(pilot, lambda: table.selected == "/odom")
            detail = app.screen.query_one(TopicDetail)

            def echoed() -> bool:
                echo = app.frame.topics.echo
                return echo is not None and echo[0] == "/odom" and echo[1].startswith('{"header"')

            assert await until(pilot, echoed, timeout=10)
            await pilot.pause(0.1)
            assert '{"header"' in str(detail.render())
            polls = app.frame.topics.polls
            await pilot.press("1")
            await pilot.pause(1.5)
            assert app.frame.topics.polls <= polls + 1  # at most the poll in flight when the screen was left
            assert app.session.echo.current is None and app.session.echo._cancel is None
    finally:
        link.close()
        backend.stop()
