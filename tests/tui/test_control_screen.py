"""The screen a user drives from: the map shows where g will take the robot, values that are not live are
marked stale, and a large terminal shows the dashboard (control, comparison and latency at once)."""

import time

import pytest

from arbiter_core.controllers import MISSIONS
from arbiter_core.kinematics import Pose
from arbiter_tui.analytics.labels import STAT_LABELS, format_stat
from arbiter_tui.analytics.store import STATS_FIELDS
from arbiter_tui.link.base import CONNECTED, RECONNECTING
from arbiter_tui.shell.screens.control import ControlScreen
from arbiter_tui.shell.widgets.analytics import CompareTable
from arbiter_tui.shell.widgets.plots import ErrorPlot, LatencyHistogram, LatencyPlot, LiveMap, TrajectoryPlot
from arbiter_tui.shell.widgets.text import (
    CARDS,
    ClientLine,
    RobotPanel,
    StatsCards,
    TrackerCards,
    TrackerLine,
    fmt_ms,
)

from ..support.tui import RecordingLink, still_app, until


def text_of(widget) -> str:
    return str(widget.render())


async def test_the_map_shows_the_mission_where_g_will_take_the_robot():
    """Missions run from where the robot stands: before g, the waypoints and the goal shown are those g
    drives to (not the mission's own frame at the origin), and after g they are the same points."""
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        app.session.link.telemetry.pose = Pose(1.0, 1.0, 0.0)
        await pilot.press("a")  # go_to_goal, the square selected
        app.refresh_frame(force=True)
        await pilot.pause()
        shown = app.frame.map
        assert shown.waypoints == ((3.0, 1.0), (3.0, 3.0), (1.0, 3.0), (1.0, 1.0))
        assert shown.goal == (3.0, 1.0) and app.frame.robot.goal == (3.0, 1.0)
        assert app.frame.robot.e_d == 2.0  # measured to that goal, 2 m ahead
        live_map = app.screen.query_one(LiveMap)
        assert await until(pilot, lambda: live_map.view is not None and live_map.view.goal == (3.0, 1.0))
        assert "G goal" in str(live_map.border_subtitle) and "+ origin" in str(live_map.border_subtitle)
        await pilot.press("g")
        assert app.session.loop.running and [tuple(p) for p in app.session.loop.mission.waypoints] == list(
            shown.waypoints
        )
        # another mission chosen while the robot stands elsewhere: its waypoints move with the robot
        await pilot.press("space")
        app.session.link.telemetry.pose = Pose(-2.0, 0.5, 0.0)
        await pilot.press(*"n" * len(MISSIONS))  # round every mission back to square: no run to resume
        app.refresh_frame(force=True)
        assert app.frame.map.waypoints[0] == (0.0, 0.5)


async def test_manual_driving_shows_no_goal_and_resuming_shows_the_interrupted_mission():
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        app.refresh_frame(force=True)
        assert app.frame.map.goal is None and app.frame.map.waypoints == () and app.frame.robot.goal is None
        await pilot.press("a", "g")
        first_goal = app.session.loop.mission.goal
        await pilot.press("i")  # a movement key takes over: manual, the mission interrupted
        assert app.session.loop.algorithm == "manual" and not app.session.loop.running
        app.session.link.telemetry.pose = Pose(5.0, 5.0, 0.0)
        app.refresh_frame(force=True)
        assert app.frame.map.goal == first_goal  # g resumes it: that goal, not a square from (5, 5)


async def test_values_that_are_not_live_are_marked_stale_and_the_rows_stay_in_view():
    link = RecordingLink(state=CONNECTED)
    app = still_app(link=link)
    async with app.run_test(size=(80, 24)) as pilot:
        app.refresh_frame(force=True)
        await pilot.pause()
        panel = app.screen.query_one(RobotPanel)
        assert not app.frame.robot.stale and "stale" not in text_of(panel)
        link._state = RECONNECTING
        app.refresh_frame(force=True)
        await pilot.pause()
        text = text_of(panel)
        assert app.frame.robot.stale and app.frame.map.stale
        assert "Pose*" in text and "Odom*" in text and "* stale" in text and "LINK DOWN" in text
        # every row of the panel is still inside it at 80x24: the banner pushed none of them out
        assert panel.region.bottom <= app.screen.query_one("#panel").content_region.bottom
        for row in ("Goal", "Errors", "Mission"):
            assert row in text
        live_map = app.screen.query_one(LiveMap)
        assert await until(pilot, lambda: "robot (stale)" in str(live_map.border_subtitle))


async def test_a_large_terminal_shows_the_dashboard_and_the_arrows_still_drive():
    app = still_app()
    async with app.run_test(size=(200, 60)) as pilot:
        screen = app.screen
        assert isinstance(screen, ControlScreen) and screen.dashboard and screen.has_class("dashboard")

        def panes_shown() -> bool:  # made the first time the terminal is large enough
            tables, cards = screen.query(CompareTable), screen.query(TrackerCards)
            return bool(tables and tables.first().row_count and cards and cards.first().region.height)

        assert await until(pilot, panes_shown)
        table = screen.query_one(CompareTable)
        assert table.display and table.row_count > 0  # the seeded runs, ranked
        assert "one-way, last" in text_of(screen.query_one(TrackerCards))
        assert screen.query_one(LatencyPlot).draws >= 1
        assert app.focused is None or app.focused is not table
        await pilot.press("up")  # drives: the table never takes the arrows here
        assert app.session.loop.command[0] > 0 and app.session.link.sent[-1][0] > 0
        await pilot.press("space")
    small = still_app()
    async with small.run_test(size=(159, 45)) as pilot:
        await pilot.pause()
        assert not small.screen.dashboard and not small.screen.query("#dash")  # not even made


def shown_lines(widget) -> list[str]:
    """The widget's lines as the terminal shows them: wrapped at its width, cut at its height."""
    from textual.geometry import Region

    return [strip.text.rstrip() for strip in widget.render_lines(Region(0, 0, *widget.outer_size))]


PANES = (("drive", "#drive"), ("err", ErrorPlot), ("lat", LatencyPlot), ("traj", TrajectoryPlot),
         ("hist", LatencyHistogram))  # fmt: skip


async def dashboard_at(size: tuple[int, int]) -> dict[str, object]:
    """What the dashboard shows at ``size``: each figure's line, and the regions of its parts."""
    app = still_app()
    async with app.run_test(size=size) as pilot:
        screen = app.screen

        def ready() -> bool:
            tables, plots = screen.query(CompareTable), screen.query(LatencyPlot)
            return bool(tables and tables.first().row_count and plots and plots.first().draws)

        assert await until(pilot, ready)
        await pilot.pause()
        table = screen.query_one(CompareTable)
        live_map = screen.query_one(LiveMap)
        x_axis, y_axis = live_map._axes(app.frame.map)
        xs, ys = zip(*app.session.loop.trail.points, (0.0, 0.0), app.frame.map.pose[:2], strict=False)
        return {
            "cards": shown_lines(screen.query_one(StatsCards)),
            "stats": app.frame.analytics.stats,
            "latency": [
                line
                for kind in (TrackerLine, TrackerCards, ClientLine)
                for line in shown_lines(screen.query_one(kind))
            ],
            "summary": app.frame.latency.summary,
            "offset": app.frame.latency.meter.offset,
            "table": (table.max_scroll_x, table.max_scroll_y, len(table.columns), len(table.table.headers)),
            "table_inside": screen.query_one("#dash-compare").region.contains_region(table.region),
            # how much of the map's axes the drawn things span, across and up (1: all of it)
            "map_fill": (
                (max(xs) - min(xs)) / (x_axis.hi - x_axis.lo),
                (max(ys) - min(ys)) / (y_axis.hi - y_axis.lo),
            ),
            "heights": {
                name: max((w.region.height for w in screen.query(kind)), default=0) for name, kind in PANES
            },
        }


async def test_every_figure_of_the_dashboard_reads_whole_at_160x45_and_200x60():
    """At both sizes every card's label sits on the row of its value, the latency pane keeps its
    max / p95 / stddev row and the clock-offset line, the comparison table shows every column and row
    (nothing to scroll to), and the map spans its drawing rather than blank metres. At 200x60 the extra
    rows go to the plots (a trajectory and a histogram join them); the control panel's rows stay."""
    shown = {size: await dashboard_at(size) for size in ((160, 45), (200, 60))}
    for size, d in shown.items():
        for name in STATS_FIELDS:
            card = f"{STAT_LABELS[name].short} {format_stat(name, getattr(d['stats'], name))}"
            assert any(card in line for line in d["cards"]), (size, card, d["cards"])
        summary = d["summary"]
        for key, label in CARDS:
            value = getattr(summary, key.removesuffix("_ms"))
            card = f"{label} {value if key == 'count' else fmt_ms(value)}"
            assert any(card in line for line in d["latency"]), (size, card, d["latency"])
        row = [line for line in d["latency"] if "max " in line]
        assert len(row) == 1 and "p95 " in row[0] and "stddev " in row[0], (size, d["latency"])
        clock = f"clock {d['offset'].offset_ms:+.1f} ms ± {d['offset'].uncertainty_ms:.1f} ms"
        assert any(line.strip().startswith(clock) for line in d["latency"]), (size, d["latency"])
        assert any("CLOCK OFFSET" in line for line in d["latency"]), (size, d["latency"])
        assert any("raw one-way p50 12.220 ms" in line for line in d["latency"]), (size, d["latency"])
        scroll_x, scroll_y, columns, headers = d["table"]
        assert (scroll_x, scroll_y) == (0, 0) and columns == headers and d["table_inside"], (size, d["table"])
        assert min(d["map_fill"]) >= 0.5, (size, d["map_fill"])
    small, big = shown[(160, 45)]["heights"], shown[(200, 60)]["heights"]
    assert small["drive"] == big["drive"]
    assert big["lat"] - small["lat"] >= 14 and big["err"] - small["err"] >= 14, (small, big)
    assert small["traj"] == small["hist"] == 0 and big["traj"] == big["err"] and big["hist"] == big["lat"]


def every_controller_on_every_mission():
    """A store of one run of each controller on each mission (the widest names, the most rows)."""
    from dataclasses import replace

    from arbiter_tui.analytics.runs import ABORTED, COMPLETED
    from arbiter_tui.analytics.store import AnalyticsStore
    from arbiter_tui.analytics.tracking import reference_path
    from arbiter_tui.session.compare import AUTONOMOUS, run_one

    store = AnalyticsStore(max_data_points=2000)
    store.start_collection()
    t0 = 1_800_000_000_000.0
    for mission in MISSIONS:
        for algorithm in AUTONOMOUS:
            result = run_one(algorithm, mission)
            points = result.points
            path = reference_path((0.0, 0.0), MISSIONS[mission])
            run = store.begin_run(algorithm, mission, t0 + points[0].timestamp - 100, path)
            for p in points[::5]:
                store.record(replace(p, timestamp=t0 + p.timestamp, runId=run))
            outcome = COMPLETED if result.completed else ABORTED
            store.end_run(outcome, t0 + points[-1].timestamp, result.final_error_m)
            t0 += points[-1].timestamp + 1000
    store.stop_collection()
    return store


@pytest.mark.parametrize("size", [(160, 45), (200, 60)], ids=["160x45", "200x60"])
async def test_the_dashboard_table_keeps_every_column_with_every_controller_on_every_mission(size):
    """The longest controller name in the table: still no column cut; the rows beyond its share of the
    height scroll, the plots below keep their rows."""
    app = still_app(store=every_controller_on_every_mission())
    async with app.run_test(size=size) as pilot:
        screen = app.screen
        assert await until(pilot, lambda: bool(screen.query(CompareTable)))
        table = screen.query_one(CompareTable)
        assert await until(pilot, lambda: table.row_count > 20)
        await pilot.pause()
        assert any("regulated_pure_pursuit" in cell for row in table.table.rows for cell in row)
        assert table.max_scroll_x == 0, (table.virtual_size, table.scrollable_content_region)
        assert screen.query_one(ErrorPlot).region.height >= 6


async def test_the_dashboard_latency_lines_take_as_many_rows_as_they_have_whenever_they_change():
    """The client line is sized to its lines when they change, not only when the terminal is resized: the
    link going down leaves the rows of its one line, coming back shows every figure again, the clock line
    included."""
    link = RecordingLink()
    app = still_app(link=link)
    async with app.run_test(size=(160, 45)) as pilot:
        assert await until(pilot, lambda: bool(app.screen.query(ClientLine)))
        client = app.screen.query_one(ClientLine)

        def clock_shown() -> bool:
            return any(line.strip().startswith("clock ") for line in shown_lines(client))

        assert await until(pilot, clock_shown)
        rows = client.region.height
        link._state = RECONNECTING
        app.refresh_frame(force=True)
        down = [
            "this console",
            "ROSBRIDGE LINK RECONNECTING: no commands, no round trips",
            "sent 20",
            "lost 0",
        ]

        def down_shown() -> bool:  # every row of the link-down line, and no blank row under it
            lines = [line.strip() for line in shown_lines(client)]
            return all(part in " ".join(lines) for part in down) and all(lines)

        assert await until(pilot, down_shown), shown_lines(client)
        assert client.region.height < rows
        link._state = CONNECTED
        app.refresh_frame(force=True)
        assert await until(pilot, lambda: client.region.height == rows and clock_shown()), shown_lines(client)


def test_a_line_of_figures_breaks_between_its_parts_never_inside_one():
    from rich.text import Text

    from arbiter_tui.shell.widgets.text import fit_lines

    line = Text.assemble(("this console", "bold"), " · rtt p50 0.600 ms · jitter 0.032 ms\nclock +1.0 ms")
    fitted = fit_lines(line, 31)
    lines = ["this console · rtt p50 0.600 ms", "  jitter 0.032 ms", "clock +1.0 ms"]
    assert fitted.plain.split("\n") == lines
    assert fitted.spans[0].end == len("this console") and fitted.spans[0].style == "bold"  # styles kept
    assert fit_lines(line, 200).plain == line.plain  # what fits is left alone
    assert fit_lines(Text("one long part · b"), 5).plain == "one long part\n  b"  # too wide alone: wraps
    sync = Text("time sync: this host adjtimex NOT synchronised, robot host chrony ±0.1 ms [0.0, 0.2]")
    assert (
        fit_lines(sync, 50).plain
        == "time sync: this host adjtimex NOT synchronised,\n  robot host chrony ±0.1 ms [0.0, 0.2]"
    )
    intervals = Text("p50 [0.000, 0.590] p95 [0.019, 0.690]")
    assert fit_lines(intervals, 20).plain == "p50 [0.000, 0.590]\n  p95 [0.019, 0.690]"  # never inside [ ]


async def test_the_dashboard_comes_and_goes_with_the_terminal_size():
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        assert not app.screen.dashboard
        await pilot.resize_terminal(200, 60)
        assert await until(pilot, lambda: app.screen.dashboard)
        assert await until(pilot, lambda: app.screen.query_one(CompareTable).row_count > 0)
        await pilot.resize_terminal(100, 30)
        assert await until(pilot, lambda: not app.screen.dashboard)


def key_words(key: str) -> str:
    """A binding's key as README and help write it."""
    words = {"question_mark": "?", "space": "space", "delete": "delete", "slash": "/", "escape": "esc"}
    return words.get(key, key)


def test_readme_and_help_name_every_key_the_screens_bind():
    """README's key table, the help screen and the bindings (what the footer shows) agree: every bound
    key is named in its screen's README row and in the help text, with the screen's action."""
    from pathlib import Path

    from arbiter_tui.shell.app import ArbiterApp
    from arbiter_tui.shell.screens.analytics import AnalyticsScreen
    from arbiter_tui.shell.screens.help import HELP
    from arbiter_tui.shell.screens.topics import TopicsScreen

    readme = Path(__file__).resolve().parents[2].joinpath("README.md").read_text()
    table = readme[readme.index("## Keys") :].split("\n\n", 1)[0]
    rows = {line.split("|")[1].strip(): line for line in table.splitlines() if line.startswith("| ")}
    where = {
        ArbiterApp: "everywhere",
        ControlScreen: "control",
        AnalyticsScreen: "analytics",
        TopicsScreen: "topics",
    }
    checked = 0
    for owner, row_name in where.items():
        row = rows[row_name]
        for binding in owner.BINDINGS:
            for key in binding.key.split(","):
                words = key_words(key)
                assert f"`{words}" in row or f"/{words}`" in row, f"README {row_name} row lacks {words}"
                assert words in HELP, f"help lacks {words}"
                checked += 1
    assert checked >= 21


async def test_readme_names_the_missions_n_cycles_and_the_algorithms_a_cycles_in_their_order():
    """README's control row said ``n`` cycled two missions (square, figure_eight); it cycles four."""
    from pathlib import Path

    readme = Path(__file__).resolve().parents[2].joinpath("README.md").read_text()
    row = next(line for line in readme.splitlines() if line.startswith("| control |"))
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        missions, algorithms = [app.session.loop.mission_name], [app.session.loop.algorithm]
        for _ in range(8):
            await pilot.press("n")
            missions.append(app.session.loop.mission_name)
            await pilot.press("a")
            algorithms.append(app.session.loop.algorithm)
    cycle = missions[: missions.index(missions[0], 1)]  # once round
    assert len(cycle) == 4 and f"`n` mission ({', '.join(cycle)})" in row, (cycle, row)
    cycle = algorithms[: algorithms.index(algorithms[0], 1)]
    assert f"`a` algorithm ({', '.join(cycle)})" in row, (cycle, row)


async def test_the_map_follows_the_robot_at_most_every_follow_period_and_ends_where_it_is():
    from arbiter_tui.shell.widgets.plots import FOLLOW_S

    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        live_map = app.screen.query_one(LiveMap)
        app.refresh_frame(force=True)
        assert await until(pilot, lambda: live_map.view is not None)
        await pilot.pause(FOLLOW_S)  # the first draw is behind us
        before = live_map.draws
        started = time.monotonic()
        for i in range(1, 6):  # five cells and more in a tenth of a second, inside the axes shown
            app.session.link.telemetry.pose = Pose(1.25 - 0.2 * i, -0.5, 0.6)
            app.sample_frame()
            await pilot.pause(0.02)
        # the first move at once, the rest wait (a loaded machine may take longer over the five)
        assert live_map.draws - before <= 1 + (time.monotonic() - started) / FOLLOW_S

        def drawn_where_it_is() -> bool:
            app.sample_frame()  # the UI tick, as the live console runs it
            return live_map.view.pose[0] == 0.25

        assert await until(pilot, drawn_where_it_is, timeout=3 * FOLLOW_S)
        assert live_map.draws <= before + 2


def from_input_thread(app, *keys: str) -> None:
    """Keys as Textual's terminal driver delivers them: parsed on its input thread, then sent to the app
    (``direct_keys`` wraps the driver Textual would choose; the headless one here)."""
    import threading

    from textual import events
    from textual.drivers.headless_driver import HeadlessDriver

    from arbiter_tui.shell.keys import direct_keys

    driver = direct_keys(HeadlessDriver, lambda: app.keys)(app)

    def deliver() -> None:
        for key in keys:
            driver.process_message(events.Key(key, key if len(key) == 1 else None))

    thread = threading.Thread(target=deliver)
    thread.start()
    thread.join()


async def test_a_teleop_key_reaches_the_robot_without_waiting_for_the_ui_and_is_answered_once():
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        speed = app.session.teleop.speed
        # The UI's loop does not run while this test holds it: the command goes out all the same.
        from_input_thread(app, "i")
        assert app.session.link.sent and app.session.link.sent[-1] == (speed, 0.0)
        from_input_thread(app, "q")  # a scale key: answered twice it would scale twice
        assert (
            app.session.teleop.speed == round(speed * 1.1, 6)
            or abs(app.session.teleop.speed - speed * 1.1) < 1e-9
        )
        await pilot.pause()
        await pilot.pause()
        assert (
            abs(app.session.teleop.speed - speed * 1.1) < 1e-9
        )  # the UI showed it and did not answer it again
        assert await until(pilot, lambda: app.frame.robot.speed == round(speed * 1.1, 2))


async def test_a_teleop_key_waits_behind_a_key_the_ui_answers():
    """``a`` (the UI's) then ``i``: ``i`` does not overtake ``a`` on the input thread; both reach the UI.
    Once the UI has answered them, teleop keys go direct again."""
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        sent = len(app.session.link.sent)
        from_input_thread(app, "a", "i")
        assert len(app.session.link.sent) == sent  # nothing went direct: i is queued behind a
        assert await until(pilot, lambda: len(app.session.link.sent) > sent)  # the UI answered i
        assert await until(pilot, lambda: app.keys._queued == 0 and app.keys._direct)
        # each answered on the input thread, before the UI runs again: the zero at once, then the move
        from_input_thread(app, "space")
        assert not app.session.teleop.moving and app.session.link.sent[-1] == (0.0, 0.0)
        from_input_thread(app, "i")
        assert app.session.teleop.moving and app.session.link.sent[-1] == (app.session.teleop.speed, 0.0)


async def test_no_key_goes_direct_while_a_dialog_is_open_or_another_screen_shows():
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("t")  # the goal prompt: "." is a digit's neighbour there, not a movement key
        assert await until(pilot, lambda: app.screen.__class__.__name__ == "GoalPrompt")
        sent = len(app.session.link.sent)
        from_input_thread(app, ".", "i")
        assert len(app.session.link.sent) == sent
        await pilot.press("escape")
        await pilot.press("3")
        assert await until(pilot, lambda: app.current_mode == "latency")
        from_input_thread(app, "i")
        await pilot.pause()
        assert len(app.session.link.sent) == sent and not app.session.teleop.moving
