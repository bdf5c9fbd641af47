"""A backend killed (-9) and started again, as a robot's computer reboots or its driver restarts (issue 46,
items 2 and 3): its odometry starts a new life at the origin. Nothing moves toward a waypoint of the old
life (``g`` starts the mission afresh from where the robot stands, and says so); the record has a gap
there -- no stale samples while the link was down, and no path length across the jump -- so the path
length is the length driven."""

import itertools
import math

from arbiter_tui.analytics.exports import parse_csv, to_csv
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED, DISCONNECTED, RECONNECTING
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.settings import CONNECT, Settings
from arbiter_tui.shell.app import make_app

from ..support.backend import start_backend
from ..support.tui import until

SIZE = (100, 30)


async def hold(pilot, key: str, seconds: float) -> None:
    for _ in range(round(seconds / 0.1)):  # auto-repeat within the key timeout
        await pilot.press(key)
        await pilot.pause(0.1)


def restart(backend):
    backend.proc.kill()
    backend.proc.wait()
    return backend


async def test_a_restarted_backend_leaves_a_gap_and_no_mission_of_its_old_life(tmp_path):
    backend = start_backend()
    ports = ("--bridge-port", str(backend.bridge_port), "--api-port", str(backend.api_port))
    link = RosLink("127.0.0.1", backend.bridge_port)
    settings = Settings(mode=CONNECT, handle_signals=False, export_dir=tmp_path)
    app = make_app(settings, link, TrackerClient(backend.api))
    store = app.session.store
    try:
        async with app.run_test(size=SIZE) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 15)
            still = lambda: max(abs(link.telemetry.v), abs(link.telemetry.w)) < 0.005  # noqa: E731

            # -- drive 1 by hand, then the backend dies and comes back (odometry at the origin again)
            await hold(pilot, "i", 1.2)
            assert await until(pilot, still, timeout=5)
            first = link.telemetry.pose.x
            assert first > 0.3
            restart(backend)
            assert await until(pilot, lambda: link.state in (DISCONNECTED, RECONNECTING), timeout=5)
            before = len(store)
            await pilot.pause(2.5)  # the link is down: 25 samples' worth of time
            assert len(store) == before, "no sample of a pose that is not live"
            backend = start_backend(*ports)
            assert await until(pilot, lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 15)
            assert await until(pilot, lambda: abs(link.telemetry.pose.x) < 1e-6, timeout=5)  # a new life

            # -- drive 2, from the new origin
            await hold(pilot, "i", 0.8)
            assert await until(pilot, still, timeout=5)
            second = link.telemetry.pose.x
            assert await until(pilot, lambda: store.points()[-1].x == second, timeout=5)
            points = store.points()
            gaps = [p for p in points if p.gap]
            assert len(gaps) == 1 and abs(gaps[0].x) < 0.01  # the first sample of the new life
            times = [p.timestamp for p in points]
            assert max(b - a for a, b in itertools.pairwise(times)) > 2000  # a gap in time
            # the path is what was driven: no stale repeats, no jump back to the origin counted
            driven = first + second
            path = store.stats().totalPathLength
            assert math.isclose(path, driven, rel_tol=0.02), (path, driven)
            # the export says where the gap is, and reads back to the same figures
            again = parse_csv(to_csv(points))
            assert [p.gap for p in again] == [p.gap for p in points]

            # -- a mission cut by the restart is forgotten: g starts it afresh from here
            app.session.select_algorithm("stanley")
            app.session.select_mission("corner")
            await pilot.press("g")
            assert app.session.loop.running
            assert await until(pilot, lambda: link.telemetry.pose.x > second + 0.3, timeout=5)
            restart(backend)
            assert await until(pilot, lambda: not app.session.loop.running, timeout=5)  # the link lost
            backend = start_backend(*ports)
            assert await until(pilot, lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 15)
            assert await until(pilot, lambda: abs(link.telemetry.pose.x) < 1e-6, timeout=5)
            await pilot.pause(0.5)
            assert still(), "nothing moves before a key"
            assert app.session.loop.interrupted is None  # nothing of the old life to resume
            await pilot.press("g")
            mission = app.session.loop.mission
            assert mission.running and not mission.resumed and mission.index == 0
            assert mission.waypoints[0] == (6.0, 0.0)  # the corner from the new origin, not the old one
            notices = [str(n.message) for n in app._notifications]
            assert any("starts afresh from here" in n and "the link was lost" in n for n in notices), notices
    finally:
        link.close()
        backend.stop()
