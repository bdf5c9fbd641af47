"""Every line fits where it is shown (issue 46): the control panel at every width, the latency figures,
the analytics plots and table, the topics columns, the help dialog. Pilot checks of what each widget
draws, and snapshots where it is about layout."""

from dataclasses import replace

import pytest
from rich.cells import cell_len

from arbiter_core.timesync import TimeSync
from arbiter_tui.session.views import RobotView
from arbiter_tui.shell.widgets.text import LABEL, ClientLine, RobotPanel, TrackerLine

from ..support.tui import show_frame, still_app, until

SIZES = [(80, 24), (120, 36), (200, 60)]
IDS = ["80x24", "120x36", "200x60"]
# the longest of every row: the longest algorithm's name and a state, a pose 10 m and more from the
# origin, a figure eight done, an error of metres
LONG = RobotView(
    v_cmd=0.5, w_cmd=-1.0, speed=0.5, turn=1.0, x=12.34, y=-15.0, theta=-3.14, v_odom=0.5, w_odom=-1.0,
    algorithm="regulated_pure_pursuit", state="stopped", mission="figure_eight", done=16, total=16,
    finished="done: 16/16 in 45.3 s", goal=(14.54, -104.31), e_d=15.17, e_th=-3.14,
)  # fmt: skip


async def shown_panel(pilot, view: RobotView) -> list[str]:
    show_frame(pilot.app, robot=view)
    await pilot.pause()
    panel = pilot.app.screen.query_one(RobotPanel)
    await pilot.pause()
    return panel.render().plain.splitlines()


@pytest.mark.parametrize("size", SIZES, ids=IDS)
async def test_every_row_of_the_control_panel_fits_its_width_and_no_word_stands_alone(size):
    """At 120 and 200 columns the rows took more than the panel (``Algo regulated_pure_pursuit`` over
    ``(stopped)``; ``rad`` alone once |x| >= 10): now each row fits, in its short form where the panel is
    narrow, and a row broken in two never leaves a word alone on the second."""
    app = still_app()
    async with app.run_test(size=size) as pilot:
        lines = await shown_panel(pilot, LONG)
        panel = app.screen.query_one(RobotPanel)
        width = panel.content_size.width
        assert all(cell_len(line) <= width for line in lines), (width, lines)
        for line in lines:
            if line.startswith(" " * LABEL):  # a row's continuation: never a single word
                assert len(line.split()) >= 2, lines
        labels = [line.split()[0] for line in lines if not line.startswith(" ")]
        assert labels == ["Command", "Max", "Pose", "Odom", "Algo", *(["State"] if width < 41 else []),
                          "Mission", "Goal", "Errors"], lines  # fmt: skip
        text = "\n".join(lines)
        assert "stopped" in text and "done: 16/16 in 45.3 s" in text and "x +12.34 y -15.00 θ -3.14" in text
        if size[0] >= 100:  # wide enough for every row's long form
            assert "Algo     regulated_pure_pursuit (stopped)" in text
            assert "θ -3.14 rad" in text and "Mission  figure_eight done: 16/16 in 45.3 s" in text
            assert panel.region.height >= len(lines)  # every row shown


@pytest.mark.parametrize("size", [(80, 24), (120, 36)], ids=["80x24", "120x36"])
def test_the_control_panel_with_its_longest_rows(snap_compare, size):
    async def longest(pilot):
        await shown_panel(pilot, LONG)

    assert snap_compare(still_app(), terminal_size=size, run_before=longest)


UNSYNCED = TimeSync("adjtimex", False)
WHOLE = (  # phrases that were broken at 80 columns, each to be read on one line
    "raw one-way p50 12.220 ms",
    "lost 0 in 10 s (0 total)",
    "robot host adjtimex NOT synchronised",
    "CLOCK OFFSET +11.9 ms exceeds 10 ms: raw one-way figures include it",
)


@pytest.mark.parametrize("size", SIZES, ids=IDS)
async def test_the_latency_figures_break_between_whole_parts_and_none_is_cut(size):
    """At 80x24 the console's line broke mid-phrase (``raw one-way`` / ``p50 12.220 ms``, ``(0`` /
    ``total)``) and the time sync line was cut: each line now breaks between its parts, every row shown."""
    app = still_app()
    async with app.run_test(size=size) as pilot:
        await pilot.press("3")
        show_frame(app, latency=replace(app.frame.latency, local_sync=UNSYNCED, robot_sync=UNSYNCED))
        await pilot.pause()
        await pilot.pause()
        for widget in (app.screen.query_one(TrackerLine), app.screen.query_one(ClientLine)):
            lines = widget.render().plain.rstrip("\n").splitlines()
            width = widget.content_size.width
            assert all(cell_len(line) <= width for line in lines), (width, lines)
            assert widget.content_size.height >= len(lines), lines  # not cut at the bottom
        text = app.screen.query_one(ClientLine).render().plain.splitlines()
        for phrase in WHOLE:
            assert any(phrase in line for line in text), (phrase, text)


def test_the_latency_screen_at_80x24_with_every_line(snap_compare):
    async def with_time_sync(pilot):
        await pilot.press("3")
        app = pilot.app
        show_frame(app, latency=replace(app.frame.latency, local_sync=UNSYNCED, robot_sync=UNSYNCED))
        await pilot.pause()

    assert snap_compare(still_app(), terminal_size=(80, 24), run_before=with_time_sync)


async def test_the_analytics_trajectory_has_rows_enough_at_80x24():
    """At 80x24 the trajectory was 3 rows on a -10...10 axis: at equal aspect the metres per row (the
    path's height over 3 rows) set the metres per column, so 29 columns spanned 36 m. The plots now keep
    at least 10 rows on a short terminal (the comparison above them scrolls), 5 of them for the path."""
    from arbiter_tui.shell.widgets.plots import TrajectoryPlot

    app = still_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("2")
        plot = app.screen.query_one(TrajectoryPlot)
        assert await until(pilot, lambda: plot.draws >= 1)
        _cols, rows = plot.scale_size()
        assert rows >= 5, rows
        assert plot._user_x_max - plot._user_x_min <= 16.0, (plot._user_x_min, plot._user_x_max)


@pytest.mark.parametrize("size", [(120, 36), (200, 60)], ids=["120x36", "200x60"])
async def test_the_analytics_table_is_full_where_it_fits_and_compact_where_it_would_scroll(size):
    """At 120x36 the full table needed sideways scrolling while the compact one fits (the switch was at a
    fixed 104 columns): the full view is shown only where all of it fits."""
    from arbiter_tui.shell.widgets.analytics import CompareTable

    app = still_app()
    async with app.run_test(size=size) as pilot:
        await pilot.press("2")
        table = app.screen.query_one(CompareTable)
        assert await until(pilot, lambda: table.row_count > 0)
        await pilot.pause()
        assert table.compact == (size[0] < 160)
        assert table.max_scroll_x == 0, (table.virtual_size, table.scrollable_content_region)
        await pilot.press("v")  # per run: its own columns, the same rule
        assert await until(pilot, lambda: table.mode == "run" and table.row_count > 0)
        await pilot.pause()
        assert table.max_scroll_x == 0, (table.virtual_size, table.scrollable_content_region)


@pytest.mark.parametrize("size", [(120, 36), (200, 60)], ids=["120x36", "200x60"])
async def test_topic_types_are_whole_where_the_name_column_has_room(size):
    """At 120x36 ``sensor_msgs/LaserSc…`` was cut while the name column had 20 columns to spare: the free
    columns go to the name and the type, each up to its longest cell."""
    from arbiter_core.topicstats import TopicFigures
    from arbiter_tui.latency.topics_table import short_type
    from arbiter_tui.shell.widgets.topics import TopicsList

    from .test_topics_screen import STATE, topics_app

    events = TopicFigures("/parameter_events", "rcl_interfaces/msg/ParameterEvent", "quiet", 3, 3, 0, 40)
    app = topics_app(replace(STATE, topics=(*STATE.topics, events)))
    async with app.run_test(size=size) as pilot:
        await pilot.press("4")
        table = app.screen.query_one(TopicsList)
        assert await until(pilot, lambda: "/parameter_events" in table.render().plain)
        lines = table.render().plain.splitlines()[1:]
        for t in table.rows():
            line = next(line for line in lines if line.startswith(t.name + " "))
            assert f" {short_type(t.type)} " in line and "…" not in line, line


@pytest.mark.parametrize("size", SIZES, ids=IDS)
async def test_the_help_shows_one_scrollbar_against_its_frame_and_none_where_it_fits(size):
    """The help's frame was thick (a solid bar each side) and its scrollbar floated in the padding beside
    it: two bars on the right, read as two thumbs. Now the frame is a line, the scrollbar the only bar,
    against the frame and the whole height inside it, and there is none where the help fits."""
    from textual.containers import VerticalScroll

    from arbiter_tui.shell.screens.help import HelpScreen

    app = still_app()
    async with app.run_test(size=size) as pilot:
        await pilot.press("question_mark")
        assert await until(pilot, lambda: isinstance(app.screen, HelpScreen))
        await pilot.pause()
        scroll = app.screen.query_one(VerticalScroll)
        bars = [w for s in app.screen_stack for w in (s, *s.walk_children()) if w.show_vertical_scrollbar]
        assert bars == ([scroll] if size[1] < 36 else []), bars
        assert {edge for edge, _ in (scroll.styles.border_left, scroll.styles.border_right)} == {"round"}
        assert scroll.styles.padding.right == 0 and scroll.styles.padding.top == 0  # the bar at the frame


@pytest.mark.parametrize("size", [(80, 24), (200, 60)], ids=["80x24", "200x60"])
async def test_the_observed_robot_side_run_and_the_topics_filter_hint_are_whole(size):
    """Issue 54, item 7: at 80 columns "pure_pursuit on corner at 0/2" ran on under the panel's labels
    ("0/2" alone at its left edge) and the topics filter's hint lost its end ("...ctrl+k stops the")."""
    from arbiter_tui.latency.autonomy import RobotSideView
    from arbiter_tui.shell.screens.topics import TopicsScreen

    from ..support.tui import screen_text

    app = still_app(observe=True, observe_label="nav2_rpp", cmd_topic="/cmd_vel_measured")
    async with app.run_test(size=size) as pilot:
        run = "regulated_pure_pursuit on figure_eight at 10/16"
        side = RobotSideView(known=True, enabled=True, running=True, text="running", run=run)
        app.sampler.robot_side_polled(side)
        app.refresh_frame(force=True)
        await pilot.pause()
        panel = app.screen.query_one(RobotPanel)
        lines = panel.render().plain.splitlines()
        width = panel.content_size.width
        robot = lines[next(i for i, line in enumerate(lines) if line.startswith("Robot")) :]
        assert all(cell_len(line) <= width for line in robot), robot
        assert all(line.startswith("Robot") or line.startswith(" " * LABEL) for line in robot), robot
        said = " ".join(" ".join(line.split()) for line in robot)
        assert said == "Robot running regulated_pure_pursuit on figure_eight at 10/16", robot
        await pilot.press("4")
        assert await until(pilot, lambda: isinstance(app.screen, TopicsScreen))
        await pilot.pause()
        hint = app.screen.query_one("#topics-filter").placeholder
        assert hint in screen_text(app), hint
