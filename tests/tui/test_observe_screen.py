"""Observe mode says what mode it is in (issue 46, item 4): a banner on every screen with what drives,
what the console watches and what a stop does; the panel shows the observed run and the robot-side
controller, never a console mission advancing from the observed robot's pose; a, n and g are offered
only where they can start something (the backend's robot-side controller); no typed goal."""

import pytest

from arbiter_tui.latency.autonomy import RobotSideView
from arbiter_tui.shell.screens.goal import GoalPrompt
from arbiter_tui.shell.widgets.text import RobotPanel

from ..support.tui import still_app, until

OBSERVE = {"observe": True, "observe_label": "nav2_rpp", "cmd_topic": "/cmd_vel_measured"}


def footer_keys(app) -> set[str]:
    return {b.binding.key for b in app.screen.active_bindings.values() if b.binding.show and b.enabled}


async def test_the_banner_panel_and_footer_of_observe_mode(tmp_path):
    app = still_app(tmp_path, **OBSERVE)
    async with app.run_test(size=(100, 30)) as pilot:
        banner = str(app.screen.query_one("#observe-banner").render())
        assert banner.startswith("OBSERVING nav2_rpp · a stop key stops the console's keys, the robot-side ")
        assert "a stop key stops the console's keys, the robot-side controller, 8 action servers' goals, " \
               "zero on /cmd_vel_measured · watching /odom /cmd_vel_measured /plan /goal_pose" \
               in banner  # fmt: skip
        app.refresh_frame(force=True)
        await pilot.pause()
        panel = str(app.screen.query_one(RobotPanel).render())
        assert "Observe  nav2_rpp (keys: stopped)" in panel and "Run      none yet" in panel
        assert "Mission" not in panel and "Goal     none (no observed run)" in panel
        assert "OBSERVING nav2_rpp" in str(app.screen.query_one("#status").render())
        # the backend runs no robot-side controller: nothing for a, n or g to start, and no goal to type
        off = RobotSideView(known=True, text="off (the backend runs without --autonomy)")
        app.sampler.robot_side_polled(off)
        app.refresh_frame(force=True)
        app.screen.refresh_bindings()
        await pilot.pause()
        assert not {"a", "n", "g"} & footer_keys(app)
        await pilot.press("g", "t")
        assert not isinstance(app.screen, GoalPrompt) and not app.session.loop.running
        # one that does: a, n and g pick and start it
        app.sampler.robot_side_polled(RobotSideView(known=True, enabled=True, text="idle"))
        app.refresh_frame(force=True)
        app.screen.refresh_bindings()
        assert await until(pilot, lambda: {"a", "n", "g"} <= footer_keys(app))
        await pilot.press("a", "n")
        app.refresh_frame(force=True)
        await pilot.pause()
        panel = str(app.screen.query_one(RobotPanel).render())
        assert "Robot    idle" in panel and "g: go_to_goal on figure_eight" in panel
        assert app.frame.map.waypoints == () and app.frame.map.goal is None  # no console mission shown
        await pilot.press("space")  # the stop keys work here too (what they did: tests/integration)
        assert app.session.loop.command == (0.0, 0.0)


@pytest.mark.parametrize("size", [(80, 24), (200, 60)], ids=["80x24", "200x60"])
def test_observe_mode_on_screen(snap_compare, size):
    app = still_app(**OBSERVE)
    app.sampler.robot_side_polled(RobotSideView(known=True, enabled=True, running=True, text="running",
                                                run="stanley on corner at 1/2"))  # fmt: skip
    assert snap_compare(app, terminal_size=size)


async def test_the_status_line_names_the_robot_side_controller_that_drives(tmp_path):
    """Issue 54, item 7: observe mode's status line said `manual` while a robot-side stanley drove."""
    app = still_app(tmp_path, **OBSERVE)
    async with app.run_test(size=(80, 24)) as pilot:
        status = lambda: str(app.screen.query_one("#status").render())  # noqa: E731
        app.sampler.robot_side_polled(
            RobotSideView(known=True, enabled=True, running=True, text="running",
                          run="stanley on corner at 0/2", algorithm="stanley")
        )  # fmt: skip
        app.refresh_frame(force=True)
        await pilot.pause()
        assert "robot-side stanley" in status() and "manual" not in status(), status()
        ended = RobotSideView(known=True, enabled=True, text="aborted", run="stanley on corner at 1/2",
                              algorithm="stanley")  # fmt: skip
        app.sampler.robot_side_polled(ended)
        app.refresh_frame(force=True)
        await pilot.pause()
        assert "robot-side" not in status() and "manual" in status(), status()
