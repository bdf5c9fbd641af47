"""Pilot tests of goals from the console (a click on the map, a typed goal, the palette, g after an
override) and of the ranked comparison (per algorithm / per run, sorting, marks, the ring warning)."""

import pytest
from textual.widgets import Static

from arbiter_tui.analytics import table as T
from arbiter_tui.analytics.runs import COMPLETED, OVERRIDDEN
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.link.sim import SimLink
from arbiter_tui.session.views import PLOT_PERIOD_S
from arbiter_tui.shell.screens.goal import GoalPrompt
from arbiter_tui.shell.widgets.analytics import CompareTable, RingWarning, RuleLine
from arbiter_tui.shell.widgets.plots import ErrorPlot, LiveMap, TrajectoryPlot

from ..support.tui import FakeClock, still_app, until

SIZE = (100, 30)


def sim_app(tmp_path):
    clock = FakeClock(0.0)
    store = AnalyticsStore()
    store.start_collection()
    app = still_app(tmp_path, link=SimLink(clock=clock), store=store)
    app.fake_clock = app.session.clock = clock  # the control loop and the simulator share one fake clock
    app.session.link.step()
    return app, clock


def drive(app, clock, seconds: float) -> None:
    """Simulated time: the simulator at 50 Hz, the control loop at 10 Hz, as the live console."""
    for n in range(round(seconds * 50)):
        clock.t = round(clock.t + 0.02, 6)
        app.session.link.step()
        if n % 5 == 4:
            app.session.tick_control()
            app.session.sample()


async def test_a_click_on_the_map_drives_to_that_point(tmp_path):
    app, clock = sim_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        app.refresh_frame(force=True)
        await pilot.pause()
        the_map = app.screen.query_one(LiveMap)
        assert await until(pilot, lambda: the_map._scale_rectangle.area > 0)
        px, py = the_map.get_pixel_from_coordinate(1.0, 0.6)  # a cell of the plot's canvas
        canvas = the_map.query_one("#plot").region
        at = (canvas.x - the_map.region.x + px, canvas.y - the_map.region.y + py)
        await pilot.click(LiveMap, offset=at)
        goal = tuple(round(v, 2) for v in the_map.get_coordinate_from_pixel(px, py))
        assert await until(pilot, lambda: app.session.loop.running)
        run = app.session.store.active_run
        assert app.session.loop.algorithm == "go_to_goal" and app.session.loop.mission.waypoints == (goal,)
        assert abs(goal[0] - 1.0) < 0.2 and abs(goal[1] - 0.6) < 0.3  # within a cell of where we aimed
        drive(app, clock, 15.0)
        pose = app.session.link.telemetry.snapshot()[0]
        assert (
            (pose.x - goal[0]) ** 2 + (pose.y - goal[1]) ** 2
        ) ** 0.5 <= app.session.loop.mission.tolerance
        assert not app.session.loop.running
        assert app.session.store.run(run).outcome == COMPLETED and app.session.store.active_run is None


async def test_a_typed_goal_and_its_errors(tmp_path):
    app, _clock = sim_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("t")
        assert isinstance(app.screen, GoalPrompt)
        await pilot.press(*"one two", "enter")
        assert isinstance(app.screen, GoalPrompt)  # stays open and says why
        assert "not numbers" in str(app.screen.query_one("#goal-error").render())
        for _ in range(7):
            await pilot.press("backspace")
        await pilot.press(*"0.5 -0.5", "enter")
        assert not isinstance(app.screen, GoalPrompt)
        assert app.session.loop.running and app.session.loop.mission.waypoints == ((0.5, -0.5),)
        assert app.session.loop.mission_label == "goal (+0.50, -0.50)"
        await pilot.press("space")
        await pilot.press("t", "escape")
        assert not isinstance(app.screen, GoalPrompt) and not app.session.loop.running


async def test_the_goal_prompt_says_where_the_robot_is_now_and_asks_before_a_far_goal(tmp_path):
    """Issue 54, item 7: the robot's position in the prompt is live, not the one at opening; a goal far
    from the robot (a typo, another frame) is asked about first and driven on a second enter."""
    from arbiter_core.kinematics import Pose

    app = still_app(tmp_path)
    telemetry, loop = app.session.link.telemetry, app.session.loop
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("t")
        what = lambda: str(app.screen.query(Static).first().render())  # noqa: E731
        assert "The robot is at +1.25 -0.50." in what()
        telemetry.pose = Pose(2.99, 0.48, 0.0)  # it drives on while the user types
        assert await until(pilot, lambda: "The robot is at +2.99 +0.48." in what(), timeout=3)
        await pilot.press(*"1000 1000", "enter")
        assert isinstance(app.screen, GoalPrompt) and not loop.running
        said = str(app.screen.query_one("#goal-error").render())
        assert said == "(+1000.00, +1000.00) is 1412 m from the robot: enter again to drive there"
        await pilot.press("enter")
        assert not isinstance(app.screen, GoalPrompt)
        assert loop.running and loop.mission.waypoints == ((1000.0, 1000.0),)
        await pilot.press("space", "t", *"3.5 1", "enter")  # a goal near the robot drives at once
        assert not isinstance(app.screen, GoalPrompt) and loop.mission.waypoints == ((3.5, 1.0),)


async def test_a_far_goals_second_enter_counts_only_once_its_question_was_drawn(tmp_path):
    """Two enters in one read (a double press, a laggy link): the second came before the question about
    the far goal was on the screen, so it answers nothing; an enter after it was drawn drives."""
    from textual import events

    app = still_app(tmp_path)
    loop = app.session.loop
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("t", *"1000 1000")
        app.post_message(events.Key("enter", "\r"))
        app.post_message(events.Key("enter", "\r"))
        await pilot.pause()
        await pilot.pause()
        assert isinstance(app.screen, GoalPrompt) and not loop.running
        await pilot.press("enter")
        assert not isinstance(app.screen, GoalPrompt) and loop.running


async def test_the_hints_name_the_controller_that_will_drive_from_the_registry(tmp_path):
    from arbiter_core.controllers import CONTROLLERS

    app, _clock = sim_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("g")  # manual selected: g starts nothing and says how to choose
        assert not app.session.loop.running
        hint = next(n.message for n in app._notifications if "Select a controller" in n.message)
        assert all(name in hint for name in CONTROLLERS)
        for _ in range(3):  # manual -> go_to_goal -> pure_pursuit -> stanley
            await pilot.press("a")
        assert app.session.loop.algorithm == "stanley"
        await pilot.press("t")
        assert isinstance(app.screen, GoalPrompt)
        assert "drive there with stanley" in str(app.screen.query_one(Static).render())
        await pilot.press(*"0.5 0", "enter")
        assert (
            app.session.loop.running
            and app.session.store.run(app.session.store.active_run).algorithm == "stanley"
        )


async def test_a_finished_run_stays_on_the_panel_until_the_next_key(tmp_path):
    from arbiter_tui.shell.widgets.text import RobotPanel

    app, clock = sim_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:

        def panel() -> str:
            app.refresh_frame(force=True)
            return str(app.screen.query_one(RobotPanel).render())

        await pilot.press("t", *"0.6 0", "enter")
        assert app.session.loop.running
        run = app.session.store.active_run
        drive(app, clock, 10.0)
        assert not app.session.loop.running
        await pilot.pause()
        first = panel()
        assert "Mission  goal (+0.60, +0.00)" in first and "done: 1/1 in " in first  # the row fits: two
        seconds = first.split("done: 1/1 in ")[1].split(" s")[0]
        assert (
            seconds == f"{app.session.store.run(run).time_s:.1f}"
        )  # the run's time, as the analytics table has it
        drive(app, clock, 5.0)  # it lasts (no 4 s toast)
        await pilot.pause()
        assert "done: 1/1 in" in panel()
        await pilot.press("k")  # any key the session takes ends it
        await pilot.pause()
        assert "done:" not in panel()


async def test_a_manual_samples_errors_are_those_the_panel_shows(tmp_path):
    """No goal on screen (manual, nothing to resume): the samples' errors are 0, not a distance to a
    waypoint nobody drives to. After an override: the interrupted goal, as the panel shows it."""
    from arbiter_core.kinematics import distance_error
    from arbiter_tui.shell.widgets.text import RobotPanel

    app, clock = sim_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:

        def panel() -> str:
            app.refresh_frame(force=True)
            return str(app.screen.query_one(RobotPanel).render())

        for _ in range(5):
            await pilot.press("i")
            drive(app, clock, 0.2)
        manual = [p for p in app.session.store.points() if p.algorithm == "manual"]
        assert manual and all(p.distanceError == 0.0 and p.headingError == 0.0 for p in manual)
        assert "Goal     none (manual)" in panel() and "Errors   —" in panel()
        drive(app, clock, 2.0)
        await pilot.press("a", "g")
        drive(app, clock, 2.0)
        await pilot.press("j")  # a movement key overrides: manual, the mission interrupted
        drive(app, clock, 0.4)
        assert app.session.loop.algorithm == "manual" and app.session.loop.interrupted is not None
        last = app.session.store.points()[-1]
        assert last.algorithm == "manual"
        goal = app.session.loop.interrupted.goal
        pose = app.session.link.telemetry.snapshot()[0]
        assert last.distanceError == pytest.approx(distance_error(pose, goal), abs=0.05)
        assert f"e_d {last.distanceError:.2f} m" in panel()


async def test_the_palette_selects_algorithm_and_mission_and_goes(tmp_path):
    app, _clock = sim_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        for text, check in (
            ("Algorithm: pure_pursuit", lambda: app.session.loop.algorithm == "pure_pursuit"),
            ("Mission: figure_eight", lambda: app.session.loop.mission_name == "figure_eight"),
            ("Go", lambda: app.session.loop.running and app.session.loop.mission_label == "figure_eight"),
        ):
            await pilot.press("ctrl+p")
            await pilot.press(*text)
            await pilot.pause(0.3)
            await pilot.press("enter")
            assert await until(pilot, check), text


async def test_g_after_an_override_resumes_and_capital_g_restarts(tmp_path):
    app, clock = sim_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("a", "g")  # go_to_goal on the square
        run = app.session.store.active_run
        drive(app, clock, 9.0)
        reached = app.session.loop.mission.index
        assert reached >= 1
        await pilot.press("i")  # a movement key takes over
        assert app.session.loop.algorithm == "manual" and app.session.store.run(run).outcome == OVERRIDDEN
        await pilot.press("space")
        await pilot.press("g")
        assert app.session.loop.running and app.session.loop.algorithm == "go_to_goal"
        assert (
            app.session.loop.mission.index == reached and app.session.loop.mission_label == "square, resumed"
        )
        await pilot.press("G")
        assert (
            app.session.loop.running
            and app.session.loop.mission.index == 0
            and app.session.loop.mission_label == "square"
        )


async def test_the_comparison_ranks_marks_sorts_and_warns(tmp_path):
    app = still_app(tmp_path)
    async with app.run_test(size=(200, 40)) as pilot:  # wide: the full table (units, a mission column)
        await pilot.press("2")
        table = app.screen.query_one(CompareTable)
        assert await until(pilot, lambda: len(table.table.rows) == 2)
        rows = table.table.rows
        # go_to_goal completed the square: best overall (the only completed), best in its columns
        # one row per (mission, algorithm): go_to_goal is best of the square (the only one that ran it)
        assert rows[0][:3] == ("square", f"{T.BEST_ROW} go_to_goal", "1/1")
        assert T.BEST_CELL in rows[0][table.table.keys.index("avgDistanceError")]
        assert rows[1][:2] == ("figure_eight", "pure_pursuit")  # never completed: no marks
        assert not any(T.BEST_CELL in c or T.BEST_ROW in c for c in rows[1])
        # no mission was completed by both: no overall best, and the line says why
        rule = str(app.screen.query_one(RuleLine).render())
        assert "no mission completed by every algorithm" in rule and table.table.best is None
        assert "avg e_d m" in table.table.headers and "time s" in table.table.headers
        warning = str(app.screen.query_one(RingWarning).render())
        assert "run 1 56 of 206" in warning and app.screen.query_one(RingWarning).display
        await pilot.press("v")  # per run
        assert await until(pilot, lambda: table.table.keys[0] == "id")
        assert [r[table.table.keys.index("outcome")] for r in table.table.rows] == ["completed", "aborted"]
        await pilot.press("s")  # sort by the next column: run id
        assert table.sort == "id"
        await pilot.click(CompareTable, offset=(2, 0))  # the header of the first column again: reversed
        assert await until(pilot, lambda: table.descending)
        # sorting orders rows within each mission; missions keep their order (one run each here)
        assert [r[0] for r in table.table.rows] == ["1", "2"]


async def test_unchanged_data_redraws_nothing(tmp_path):
    app = still_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2")
        await pilot.pause()
        table = app.screen.query_one(CompareTable)
        plots = [app.screen.query_one(TrajectoryPlot), app.screen.query_one(ErrorPlot)]
        before = (table.fills, [p.draws for p in plots])
        for _ in range(5):
            app.refresh_frame(force=True)
            await pilot.pause()
        assert (table.fills, [p.draws for p in plots]) == before
        app.session.store.start_collection()
        app.refresh_frame(force=True)
        await pilot.pause()
        before = (table.fills, [p.draws for p in plots])
        stats = app.frame.analytics.stats
        app.session.loop.sample()  # one new sample: the numbers follow at once, the plots in PLOT_PERIOD_S
        app.refresh_frame(force=True)
        await pilot.pause()
        assert app.frame.analytics.stats != stats  # the ring is full: the oldest sample gave way to the new
        assert table.fills == before[0]  # the run rows have not changed
        assert [p.draws for p in plots] == before[1]  # plotted less than PLOT_PERIOD_S ago

        def published_and_redrawn() -> bool:
            app.refresh_frame(force=True)
            return [p.draws for p in plots] != before[1]

        assert await until(pilot, published_and_redrawn, timeout=PLOT_PERIOD_S + 2, step=0.1)
        assert [p.draws for p in plots] == [d + 1 for d in before[1]] and table.fills == before[0]


async def test_a_running_mission_updates_its_row_in_place(tmp_path):
    app, clock = sim_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("a", "g", "2")
        table = app.screen.query_one(CompareTable)
        for _ in range(3):
            drive(app, clock, 1.0)
            for _ in range(10):
                app.session.loop.sample()
            app.refresh_frame(force=True)
            await pilot.pause()
        fills, shown = table.fills, table.table.rows
        drive(app, clock, 2.0)
        for _ in range(20):
            app.session.loop.sample()
        app.refresh_frame(force=True)
        await pilot.pause()
        assert table.table.rows != shown and table.fills == fills  # new figures, no rebuild
        on_screen = [str(c) for c in table.get_row("0")]
        assert on_screen == list(table.table.rows[0])  # the cells show the new row exactly
