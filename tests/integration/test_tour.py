"""One link, many views: a tour of every screen, with every row of the topics screen selected in turn,
must leave the console's own streams flowing (odometry fresh, every command the tracker recorded
counted as a round trip) — against the real backend, through roslibpy, with a mission driving.

The topics screen's echo once removed every listener of the echoed topic's name (roslibpy's
``Topic.unsubscribe`` calls ``ros.off(name)``): passing over ``/odom`` left the console driving blind,
over ``/latency_report`` every later command was counted lost."""

import time

from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED, DISCONNECTED, RECONNECTING
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell.app import make_app
from arbiter_tui.shell.widgets.topics import TopicsList

from ..support.backend import get_json, start_backend
from ..support.tui import until


def _tracker_count(api: str) -> int:
    return int(get_json(f"{api}/api/health")["records_count"])


async def _walk_topics(pilot, app, halfway=None) -> list[str]:
    """Screen 4: select every row in turn (Home, then Down), each until its echo is asked for."""
    await pilot.press("4")
    table = app.screen.query_one(TopicsList)
    wanted = {"/odom", "/latency_report", "/cmd_vel_measured", "/stamped_cmd_vel"}
    assert await until(pilot, lambda: wanted <= {t.name for t in table.rows()}, timeout=15)
    names = [t.name for t in table.rows()]
    await pilot.press("home")
    visited = []
    for i, name in enumerate(names):
        assert await until(pilot, lambda n=name: table.selected == n and app.session.echo.current is not None)
        assert app.session.echo.current[0] == name
        if name in ("/odom", "/latency_report"):  # the streams the console itself depends on: echoed
            assert await until(
                pilot,
                lambda n=name: (
                    app.session.echo.current[0] == n and app.session.echo.current[1].startswith("{")
                ),
            )
        visited.append(name)
        if halfway is not None and i == len(names) // 2:
            await halfway()
        await pilot.press("down")
    return visited


async def _assert_streams_flow(pilot, app, link: RosLink, api: str) -> None:
    """Odometry fresh and moving; every command the tracker records is a round trip, none lost."""
    count = link.telemetry.odom_count
    assert await until(pilot, lambda: link.telemetry.odom_count >= count + 5, timeout=5), "odometry stopped"
    assert not link.telemetry.odometry_missing(time.monotonic())
    assert await until(pilot, lambda: "no odometry" not in app.sampler.status().text(), timeout=3)
    await pilot.press("1", "space")  # stop the mission; then count with nothing in flight
    meter = link.telemetry.meter
    assert await until(pilot, lambda: meter.summary().in_flight == 0, timeout=5)
    matched, lost, recorded = meter.matched, meter.lost, _tracker_count(api)
    for _ in range(8):
        await pilot.press("i")
        await pilot.pause(0.05)
    assert await until(pilot, lambda: _tracker_count(api) >= recorded + 3, timeout=5)
    assert await until(pilot, lambda: meter.summary().in_flight == 0, timeout=5)
    assert await until(pilot, lambda: meter.matched - matched == _tracker_count(api) - recorded, timeout=5), (
        meter.matched - matched,
        _tracker_count(api) - recorded,
    )
    assert meter.lost == lost, "commands the tracker recorded were counted lost"


async def _start_mission(pilot, app, link: RosLink) -> None:
    assert await until(pilot, lambda: link.state == CONNECTED, timeout=15)
    assert await until(pilot, lambda: link.telemetry.odom_count > 0, timeout=10)
    await pilot.press("a", "g")  # an autonomous run: it keeps driving while the other screens show
    assert await until(pilot, lambda: link.telemetry.meter.matched >= 3, timeout=10)


async def test_a_tour_of_every_screen_and_topic_leaves_the_consoles_streams_flowing(tmp_path):
    backend = start_backend()
    link = RosLink("127.0.0.1", backend.bridge_port)
    app = make_app(Settings(handle_signals=False, export_dir=tmp_path), link, TrackerClient(backend.api))
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            await _start_mission(pilot, app, link)
            for key in ("2", "3"):
                await pilot.press(key)
                await pilot.pause(0.2)
            visited = await _walk_topics(pilot, app)
            assert {"/odom", "/latency_report"} <= set(visited)
            await pilot.press("1")
            assert await until(pilot, lambda: app.session.echo.current is None)
            assert set(link.streams.subscriptions()) == {link.topic_odom, link.topic_report}
            await _assert_streams_flow(pilot, app, link, backend.api)
    finally:
        link.close()
        backend.stop()


async def test_the_same_tour_with_the_link_dropped_and_restored_half_way(tmp_path):
    backend = start_backend()
    link = RosLink("127.0.0.1", backend.bridge_port)
    app = make_app(Settings(handle_signals=False, export_dir=tmp_path), link, TrackerClient(backend.api))
    restarted = []
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            await _start_mission(pilot, app, link)

            async def drop_and_restore() -> None:
                backend.proc.kill()
                backend.proc.wait()
                assert await until(pilot, lambda: link.state in (DISCONNECTED, RECONNECTING), timeout=5)
                restarted.append(
                    start_backend(
                        "--bridge-port", str(backend.bridge_port), "--api-port", str(backend.api_port)
                    )
                )
                assert await until(pilot, lambda: link.state == CONNECTED, timeout=10)

            for key in ("2", "3"):
                await pilot.press(key)
                await pilot.pause(0.2)
            await _walk_topics(pilot, app, halfway=drop_and_restore)
            assert restarted
            await pilot.press("1")
            await pilot.press("g")  # the mission was cut by the drop or still runs: drive again
            await _assert_streams_flow(pilot, app, link, restarted[0].api)
    finally:
        link.close()
        backend.stop()
        for b in restarted:
            b.stop()
