"""A key's echo is a frame of what the key changed: on a slow SSH link a frame's bytes are its time on
the wire, and the echo of ``q`` must not carry the map, the plots and the analytics that changed since the
last frame (docs/benchmarks/screen-bytes.md: 0.6 s at p95 through 256 kbit/s at 200x60 when it did)."""

from arbiter_core.kinematics import Pose
from arbiter_tui.shell.widgets.plots import Plot

from ..support.tui import still_app, until


async def test_a_keys_echo_is_a_frame_of_the_panel_alone_and_the_next_frame_brings_the_rest():
    app = still_app()
    async with app.run_test(size=(200, 60)) as pilot:  # the dashboard: the map, plots, analytics
        await pilot.pause()
        before = app.screen.frame
        plots = list(app.screen.query(Plot))
        assert len(plots) >= 4
        draws = [p.draws for p in plots]
        # meanwhile the robot moved and recorded: a frame sampled now would show a new map and status
        app.session.link.telemetry.pose = Pose(1.75, -0.25, 0.9)
        app.session.loop.trail.add(1.75, -0.25)
        await pilot.press("q")
        echo = app.screen.frame
        assert echo.robot.speed > before.robot.speed  # the key's change, at once
        assert echo.robot.x == 1.75  # (the panel as it is now)
        assert echo.map is before.map and echo.analytics is before.analytics
        assert echo.latency is before.latency and echo.topics is before.topics
        assert [p.draws for p in plots] == draws  # no plot redrawn for the echo
        app.sample_frame()  # the next tick's frame
        assert await until(pilot, lambda: app.screen.frame.map is not before.map)

