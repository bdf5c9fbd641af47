"""The fleet screen (arbiter_tui.fleet.app): snapshots at 80x24 and 200x60 with live, stale, lost and bad-data
rows, and the keys a user presses (Pilot): severity order, the name filter, Enter opening the single-robot
console on the advertised URLs and coming back, a lost robot not opened, the history on ``h``."""

import threading
import time

import pytest
from textual import events
from textual.widgets import Input, Static

from arbiter_core import fleet
from arbiter_core.timesync import TimeSync
from arbiter_tui.fleet.app import STOP_NOTE_S, FleetApp, FleetList
from arbiter_tui.fleet.rows import FleetModel, detail_lines

from ..support.tui import screen_text

W = 1_800_000_000.0  # 2027-01-15 08:00:00 UTC
MONO = 1000.0


@pytest.fixture(autouse=True)
def utc(monkeypatch):
    """'lost since HH:MM:SS' is local time: UTC here, so the snapshots are the same on every machine."""
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()
    yield
    monkeypatch.undo()
    time.tzset()


def status(name, **kw):
    base = dict(
        robot=name,
        t=W,
        started=W - 600,
        driver="nobody",
        mode="embedded, sim",
        rosbridge=f"ws://{name}.lab:9090",
        tracker=f"http://{name}.lab:8085",
    )
    return fleet.Status(**{**base, **kw})


def latency(name, p95, ok=True):
    return fleet.Latency(
        name,
        W,
        count=400,
        total=9000,
        p50_ms=p95 / 2,
        p95_ms=p95,
        sync_source="chrony",
        sync_ok=ok,
        sync_error_ms=0.4 if ok else None,
    )


def topics(name, *items):
    return fleet.Topics(name, W, 5.0, 12, tuple(fleet.TopicHealth(*i) for i in items))


def fleet_model():
    """Eight robots: live ones driven by a console, a robot-side controller and Nav2, one with a topic
    below its rate, one stale, two lost (one for an hour), one sending bad data."""
    m = FleetModel(console_sync=TimeSync("chrony", True, 0.01, 0.3))

    def robot(name, at=MONO, **kw):
        m.token(name, True, W - 900, MONO - 900)
        m.accept(status(name, **kw), 400, at)

    robot(
        "lab-01",
        driver="console",
        driver_detail="last command 40 ms ago",
        pose=(1.2, -0.5, 0.3),
        velocity=(0.4, 0.1),
        namespace="/lab01",
    )
    m.accept(latency("lab-01", 6.2), 200, MONO)
    m.accept(topics("lab-01", ("/cmd_vel", "quiet"), ("/odom", "ok", 50.0)), 300, MONO)
    robot(
        "lab-02",
        driver="robot",
        driver_detail="pure_pursuit on square",
        controller="pure_pursuit",
        mission="square",
        run_state="running",
        waypoint=2,
        waypoints=4,
        runs=3,
    )
    m.accept(latency("lab-02", 3.4), 200, MONO)
    grade = fleet.RunGrade(3, "stanley", "slalom", "completed", 41.2, 7, 7, 0.08, W - 300)
    m.accept(fleet.Runs("lab-02", W - 300, 3, grade), 300, MONO)
    robot("yard-07", driver="foreign", driver_detail="commands on /cmd_vel at 20 Hz")
    m.accept(latency("yard-07", 48.0, ok=False), 200, MONO)
    m.accept(topics("yard-07", ("/scan", "below", 4.1, 20.0, 10.0), ("/odom", "ok", 50.0)), 300, MONO)
    robot("lab-03", at=MONO - 12)  # its last status 12 s ago: stale
    robot("yard-02")
    m.token("yard-02", False, W - 125, MONO - 125)  # lost two minutes ago
    robot("yard-09")
    m.token("yard-09", False, W - 3700, MONO - 3700)
    robot("lab-05", driver="nobody")
    m.reject("lab-05", "latency: not JSON a robot may send: NaN (numbers must be finite)", MONO - 3)
    m.reject("lab-05", "status: 10.5 MB, over the 1.5 kB a status may be", MONO - 1)
    robot("lab-04", driver="nobody")
    m.accept(latency("lab-04", 2.1), 200, MONO)
    return m


SESSION = "router on tcp/0.0.0.0:7447"


def fleet_app(opened=None, history=None, pattern="", stop=None):
    model = fleet_model()
    calls = [] if opened is None else opened

    def opener(argv):
        calls.append(argv)
        return 0

    return FleetApp(
        source=lambda p: model.view(W, MONO, p, SESSION),
        opener=opener,
        history=history,
        pattern=pattern,
        stop=stop,
    )


@pytest.mark.parametrize("size", [(80, 24), (200, 60)], ids=["80x24", "200x60"])
def test_fleet_screen(snap_compare, size):
    assert snap_compare(fleet_app(), terminal_size=size)


def test_fleet_screen_filtered_with_a_lost_robot_selected(snap_compare):
    assert snap_compare(fleet_app(), terminal_size=(80, 24), press=["slash", "y", "a", "r", "d", "enter"])


async def test_rows_come_worst_first_and_the_filter_narrows_them():
    app = fleet_app()
    async with app.run_test(size=(120, 40)) as pilot:
        rows = app.screen.view.rows
        assert [r.name for r in rows] == [
            "yard-02",
            "yard-09",
            "lab-05",
            "lab-03",
            "yard-07",
            "lab-01",
            "lab-02",
            "lab-04",
        ]
        assert [r.state for r in rows[:4]] == ["lost", "lost", "alive", "stale"]
        assert rows[2].bad.startswith("status: 10.5 MB")
        await pilot.press("slash", *"lab-0[12]")
        await pilot.pause()
        assert [r.name for r in app.screen.view.rows] == ["lab-01", "lab-02"]
        assert "2 of 8 robots" in str(app.screen.query_one("#fleet-head").content)
        await pilot.press("escape")
        await pilot.pause()
        assert len(app.screen.view.rows) == 8


async def test_enter_opens_the_console_on_the_advertised_urls_and_comes_back():
    opened = []
    app = fleet_app(opened)
    async with app.run_test(size=(120, 40)) as pilot:
        lst = app.screen.query_one(FleetList)
        await pilot.press("enter")  # the first row: yard-02, lost
        await pilot.pause()
        assert opened == []
        assert any("yard-02 is lost since 07:57:55" in n.message for n in app._notifications)
        lst.selected = "lab-01"
        await pilot.pause()
        assert "Enter opens ws://lab-01.lab:9090" in str(app.screen.query_one("#fleet-detail").content)
        await pilot.press("enter")
        await pilot.pause()
        assert opened == [
            [
                "--robot-name",
                "lab-01",
                "--rosbridge",
                "ws://lab-01.lab:9090",
                "--tracker",
                "http://lab-01.lab:8085",
                "--namespace",
                "/lab01",
            ]
        ]
        assert app.screen.query_one(FleetList).has_focus  # back on the fleet, as it was
        assert any("back from lab-01" in n.message for n in app._notifications)


async def test_history_of_the_selected_robot_on_h():
    asked = []

    def history(name, minutes):
        asked.append((name, minutes))
        grade = fleet.RunGrade(1, "stanley", "square", "completed", 30.0, 4, 4, 0.1, W)
        return fleet.History(
            name, W, minutes, (latency(name, 2.0), latency(name, 5.0), fleet.Runs(name, W, 1, grade))
        )

    app = fleet_app(history=history)
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("down", "down", "h")
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert asked == [("lab-05", 10.0)]
        detail = str(app.screen.query_one("#fleet-detail").content)
        assert "history (10 min): 3 summaries, p95 2-5 ms, 1 runs, last stanley completed 30.0 s" in detail
        assert "bad data (2): status: 10.5 MB" in detail


def one_write(app, text):
    """Keys as one read of the terminal brings them (a paste, a laggy SSH link, a throttled Pi): all in
    the app's queue before any is handled."""
    names = {"/": "slash", "\r": "enter", "-": "minus"}
    for ch in text:
        app.post_message(events.Key(names.get(ch, ch), None if ch == "\r" else ch))


async def test_keys_typed_ahead_of_the_filters_focus_go_to_the_filter_and_open_nothing():
    opened, asked = [], []
    app = fleet_app(opened, history=lambda name, minutes: asked.append(name) or "none")
    async with app.run_test(size=(120, 40)) as pilot:
        app.screen.query_one(FleetList).selected = "lab-01"
        await pilot.pause()
        one_write(app, "/lab-02\r")
        await pilot.pause()
        await pilot.pause()
        assert app.screen.query_one("#fleet-filter").value == "lab-02"
        assert [r.name for r in app.screen.view.rows] == ["lab-02"]
        assert opened == []  # Enter ended the filter; lab-01's console was opened by nobody
        one_write(app, "/hq")  # history and quit are letters of a pattern here
        await pilot.pause()
        await pilot.pause()
        assert app.screen.query_one("#fleet-filter").value == "hq"  # the old pattern selected, replaced
        assert asked == [] and app.is_running


async def test_enter_opens_only_a_selection_that_was_drawn():
    opened = []
    app = fleet_app(opened)
    async with app.run_test(size=(120, 40)) as pilot:
        app.screen.query_one(FleetList).selected = "lab-01"
        await pilot.pause()
        app.post_message(events.Key("down", None))
        app.post_message(events.Key("enter", None))  # lab-02, selected and not yet drawn
        await pilot.pause()
        await pilot.pause()
        assert opened == []
        await pilot.press("enter")  # now it has been seen
        await pilot.pause()
        assert [argv[argv.index("--rosbridge") + 1] for argv in opened] == ["ws://lab-02.lab:9090"]


def many(n=50):
    """``n`` healthy robots r00, r01, ..."""
    m = FleetModel(console_sync=TimeSync("chrony", True, 0.01, 0.3))
    for i in range(n):
        name = f"r{i:02d}"
        m.token(name, True, W - 900, MONO - 900)
        m.accept(status(name), 400, MONO)
        m.accept(latency(name, 3.0), 200, MONO)
    return m


def drawn(app):
    return app.screen.query_one(FleetList).shown()


async def test_the_worst_rows_stay_in_sight_and_selected_as_they_sort_above():
    """30 of 50 robots go lost while the list holds 20: the first rows drawn are lost ones, the worst
    selected (before: the selection stayed on the first robot at start-up, and the list scrolled down to
    keep it in sight, the lost rows above it out of sight)."""
    m = many()
    app = FleetApp(source=lambda p: m.view(W, MONO, p, SESSION), opener=lambda a: 0)
    async with app.run_test(size=(120, 33)) as pilot:
        await pilot.pause()
        assert drawn(app)[1].startswith("r00")
        for i in range(20, 50):
            m.token(f"r{i:02d}", False, W - 5, MONO - 5)
        app.screen.sample()
        await pilot.pause()
        rows = drawn(app)[1:]
        assert rows[0].startswith("r20") and all("lost since" in r for r in rows)
        assert app.screen.query_one(FleetList).selected == "r20"
        head = str(app.screen.query_one("#fleet-head").content)
        assert "lost 30: r20, r21, r22, r23 +26 more" in head


async def test_a_person_who_scrolled_sees_how_many_worse_rows_are_above_and_home_jumps_back():
    m = many()
    app = FleetApp(source=lambda p: m.view(W, MONO, p, SESSION), opener=lambda a: 0)
    async with app.run_test(size=(120, 33)) as pilot:
        await pilot.press(*["pagedown"] * 3)  # r30, the person's choice
        assert app.screen.query_one(FleetList).selected == "r30"
        for name in ("r01", "r02", "r03"):
            m.token(name, False, W - 5, MONO - 5)
        m.reject("r04", "status: not JSON", MONO)
        app.screen.sample()
        await pilot.pause()
        lines = drawn(app)
        assert app.screen.query_one(FleetList).selected == "r30"  # it stays where the person put it
        assert lines[1] == "▲ 4 worse above (3 lost, 1 bad data) · Home: the worst first"
        assert any(line.startswith("r30") for line in lines)
        await pilot.press("home")
        lines = drawn(app)
        assert lines[1].startswith("r01") and not any("worse above" in line for line in lines)
        assert app.screen.query_one(FleetList).selected == "r01"


async def test_a_robot_going_lost_is_announced_once_and_rings_the_bell_when_asked(monkeypatch):
    m = many(5)
    app = FleetApp(source=lambda p: m.view(W, MONO, p, SESSION), opener=lambda a: 0, bell_on_lost=True)
    bells = []
    monkeypatch.setattr(app, "bell", lambda: bells.append(1))
    async with app.run_test(size=(120, 33)) as pilot:
        await pilot.pause()
        assert "all 5 alive, none in trouble" in str(app.screen.query_one("#fleet-head").content)
        m.token("r03", False, W, MONO)
        for _ in range(3):
            app.screen.sample()
            await pilot.pause()
        said = [n.message for n in app._notifications if "lost" in n.message]
        assert said == ["08:00:00 lost: r03"] and bells == [1]
        assert "lost 1: r03" in str(app.screen.query_one("#fleet-head").content)


async def test_a_lost_rows_figures_are_its_last_ones_dimmed_with_their_age_never_current():
    """yard-02, lost two minutes ago in the middle of a run: its figures read as of then."""
    from arbiter_tui.fleet.app import layout, line

    m = fleet_model()
    m.token("yard-02", True, W - 200, MONO - 200)
    running = status("yard-02", controller="stanley", run_state="running", waypoint=0, waypoints=8)
    m.accept(running, 400, MONO - 130)
    m.accept(latency("yard-02", 7.5), 200, MONO - 130)
    m.token("yard-02", False, W - 125, MONO - 125)
    row = m.row_of("yard-02", W, MONO)
    app = FleetApp(source=lambda p: m.view(W, MONO, p, SESSION), opener=lambda a: 0)
    async with app.run_test(size=(200, 40)) as pilot:
        await pilot.pause()
        drawn_line = shown_row(app, "yard-02")
        assert "stanley 0/8 was running" in drawn_line and "0/8 running" not in drawn_line
        assert "figures as of 07:57:50, 2m old" in drawn_line
        detail = str(app.screen.query_one("#fleet-detail").content)
        assert "figures as of 07:57:50, 2m old: not current (the robot is lost)" in detail
    text = line(row, layout(200), False)
    p95 = text.plain.index("7.5 ms")
    assert any(span.start <= p95 < span.end and span.style == "dim" for span in text.spans)
    assert row.to_json()["figures_at"] == W - 130


async def test_while_the_consoles_link_is_down_every_row_reads_unknown_since_and_the_header_says_why():
    m = fleet_model()
    app = FleetApp(source=lambda p: m.view(W, MONO, p, SESSION), opener=lambda a: 0)
    async with app.run_test(size=(200, 40)) as pilot:
        await pilot.pause()
        for name in m.names():  # the router's link closed: every token goes with it
            m.token(name, False, W - 0.001, MONO - 0.001)
        m.link(False, W, MONO)
        app.screen.sample()
        await pilot.pause()
        assert {r.state for r in app.screen.view.rows} == {"unknown"}
        assert "unknown since 08:00:00" in shown_row(app, "lab-01")
        head = str(app.screen.query_one("#fleet-head").content)
        assert "8 unknown: this console's link to its router is down" in head
        assert not [n for n in app._notifications if "lost:" in n.message]  # no robot said lost


def test_a_healthy_robots_worst_topic_keeps_its_verdict_when_it_is_cut():
    """Cut at its end, ``/lab_w0_000/camera/imag…`` read like a problem; its name is cut instead."""
    from arbiter_tui.fleet.app import fit_topic, layout, line

    m = FleetModel()
    m.token("lab-w0-000", True, W, MONO)
    m.accept(status("lab-w0-000"), 400, MONO)
    m.accept(topics("lab-w0-000", ("/lab_w0_000/camera/image_raw", "ok", 30.0)), 300, MONO)
    row = m.row_of("lab-w0-000", W, MONO)
    assert "…000/camera/image_raw ok " in line(row, layout(200), False).plain
    slow = fleet.TopicHealth("/lab_w0_000/camera/image_raw", "below", 4.1, None, 10.0).words()
    assert fit_topic(slow, 24) == "…era/image_raw 4.1<10 Hz"
    assert fit_topic("/scan ok", 24) == "/scan ok"


def shown_row(app, name):
    """The list's line for ``name`` as drawn."""
    drawn = app.screen.query_one(FleetList).shown()
    return next(line for line in drawn if line.startswith(name))


async def test_space_and_ctrl_k_stop_the_selected_robot_and_its_row_says_what_it_answered():
    asked = []

    def stop(name):
        asked.append(name)
        if name == "lab-02":
            return fleet.StopAnswer(name, W, "robot", True, "stanley on square at 2/4", 0)
        return f"not stopped: this console may not stop {name} (its access control on arbiter/{name}/stop)"

    app = fleet_app(stop=stop)
    async with app.run_test(size=(300, 40)) as pilot:
        app.screen.query_one(FleetList).selected = "lab-02"
        await pilot.pause()  # drawn: the person sees it selected
        await pilot.press("space")
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert asked == ["lab-02"]
        assert "stopped: stanley aborted, 0 commands, zero sent" in shown_row(app, "lab-02")
        assert "stop: " in str(app.screen.query_one("#fleet-detail").content)
        # ctrl+k reaches the selected robot from the filter too (the pattern keeps its text)
        await pilot.press("slash", *"lab-01", "ctrl+k")
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert asked == ["lab-02", "lab-01"]
        assert app.screen.query_one("#fleet-filter").value == "lab-01"
        refused = "not stopped: this console may not stop lab-01 (its access control on arbiter/lab-01/stop)"
        assert refused in shown_row(app, "lab-01")
        assert [n.message.split(" ", 1)[1] for n in app._notifications][-1:] == [refused]  # one line


async def test_stop_all_shown_asks_for_a_second_press_and_stops_the_filtered_robots_not_the_lost():
    asked = []
    app = fleet_app(stop=lambda name: asked.append(name) or fleet.StopAnswer(name, W, "nobody", True))
    async with app.run_test(size=(300, 40)) as pilot:
        await pilot.press("slash", *"yard", "enter")  # yard-02 and yard-09 lost, yard-07 alive
        await pilot.press("S")
        await pilot.pause()
        assert asked == []
        confirm = "press S again within 3 s to stop the 1 robots shown matching 'yard'"
        assert confirm in list(app._notifications)[-1].message
        await pilot.press("S")
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert asked == ["yard-07"]
        assert "stopped: nothing was driving, zero sent" in shown_row(app, "yard-07")


async def test_a_view_that_shows_the_same_text_repaints_nothing(monkeypatch):
    """Views come twice a second, each with its own clock; the list draws again only the lines whose text
    changed (an age shown in whole seconds), and the header and detail are not laid out again."""
    model, clock = fleet_model(), [0.0]
    drawn_lines, updates = [], [0]
    real_render_line, real_update = FleetList.render_line, Static.update

    def render_line(self, y):
        drawn_lines.append(y)
        return real_render_line(self, y)

    def update(self, *args, **kwargs):
        updates[0] += 1
        return real_update(self, *args, **kwargs)

    monkeypatch.setattr(FleetList, "render_line", render_line)
    monkeypatch.setattr(Static, "update", update)
    app = FleetApp(source=lambda p: model.view(W + clock[0], MONO + clock[0], p, SESSION), opener=lambda a: 0)
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.pause()
        lst = app.screen.query_one(FleetList)
        before, shown = (len(drawn_lines), updates[0]), lst.shown()
        for _ in range(3):  # 0.1 s later each time: every age shown is the same whole second
            clock[0] += 0.1
            app.screen.sample()
            await pilot.pause()
        assert (len(drawn_lines), updates[0]) == before
        clock[0] += 1.0  # the ages shown move on: those lines, and no other, are drawn again
        app.screen.sample()
        await pilot.pause()
        changed = {y for y, (a, b) in enumerate(zip(shown, lst.shown(), strict=True)) if a != b}
        assert changed and set(drawn_lines[before[0] :]) == changed
        assert len(changed) < len(shown) - 1  # not the whole list



async def test_at_80_columns_the_head_and_every_detail_line_are_whole():
    """Issue 54, item 7: at 80 columns the head's "connecting: client of ..." and the detail's longer
    lines were cut (an ellipsis, the rest lost): now each breaks between its parts, then indented."""
    from rich.cells import cell_len

    model = fleet_model()
    session = "connecting: client of tcp/192.168.100.200:7447,tcp/192.168.100.201:7447"
    app = FleetApp(source=lambda p: model.view(W, MONO, p, session), opener=lambda argv: 0)
    words = lambda text: " ".join(w for w in text.split() if w != "·")  # noqa: E731
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("slash", *"lab-0[12]", "enter")
        rows = app.screen.query_one(FleetList)
        for name in ("lab-01", "lab-02"):
            while rows.current().name != name:
                await pilot.press("down")
            await pilot.pause()
            for selector in ("#fleet-head", "#fleet-detail"):
                static = app.screen.query_one(selector, Static)
                shown = static.render().plain.splitlines()
                assert all(cell_len(line) <= static.content_size.width for line in shown), shown
                assert not any(line.endswith("…") for line in shown), shown
            head = words(str(app.screen.query_one("#fleet-head", Static).render()))
            assert head.startswith(words(f"fleet · {session} · 2 of 8 robots")), head
            detail = str(app.screen.query_one("#fleet-detail", Static).render())
            row = rows.current()
            for line in detail_lines(row, W):  # every word of every line is on the screen, in order
                assert words(line) in words(detail), (line, detail)


async def test_the_console_opened_from_the_fleet_says_which_robot_it_drives(tmp_path):
    """Issue 54, item 7: the console the fleet opened never showed the robot's name; the fleet passes it
    (--robot-name) and the status line says it first, at 80 columns too."""
    from arbiter_tui.launch import parse

    from ..support.tui import still_app

    opened: list[list[str]] = []
    app = fleet_app(opened)
    async with app.run_test(size=(80, 24)) as pilot:
        app.screen.query_one(FleetList).selected = "lab-01"
        await pilot.pause()
        await pilot.press("enter")
        await pilot.pause()
    (tmp_path / "empty.toml").write_text("")
    args, _loaded, _cli = parse([*opened[0], "--config", str(tmp_path / "empty.toml")])
    assert args.robot_name == "lab-01"
    console = still_app(tmp_path, robot_name=args.robot_name)
    async with console.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        status = str(console.screen.query_one("#status").render())
        assert status.startswith("CONNECTED · lab-01 · "), status


async def test_a_stop_goes_to_the_robot_drawn_selected_not_to_one_that_went_lost_since():
    """A robot goes lost between a paint and the space key: it sorts first and takes the selection,
    but the person saw r00 selected, and the stop goes to r00 (before: to r03, the selection then)."""
    asked = []
    m = many(5)
    app = FleetApp(
        source=lambda p: m.view(W, MONO, p, SESSION),
        opener=lambda a: 0,
        stop=lambda name: asked.append(name) or fleet.StopAnswer(name, W, "nobody", True),
    )
    async with app.run_test(size=(120, 33)) as pilot:
        await pilot.pause()
        assert app.screen.query_one(FleetList).selected == "r00"
        m.token("r03", False, W, MONO)
        app.screen.sample()  # r03 lost: first, selected; not drawn yet
        app.post_message(events.Key("space", " "))
        await pilot.pause()
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert asked == ["r00"]


async def test_while_typing_a_filter_the_footer_names_ctrl_k():
    app = fleet_app(stop=lambda name: fleet.StopAnswer(name, W, "nobody", True))
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("slash", "l")
        await pilot.pause()
        assert isinstance(app.focused, Input) and app.focused.value == "l"
        footer = screen_text(app).splitlines()[-1]
        assert "^k Stop robot" in footer, footer


async def test_a_stops_note_goes_away_after_a_while_and_a_refusal_is_styled_by_a_flag_not_its_words():
    now = [MONO]
    m = many(3)
    answers = {"r00": "not stopped: this console may not stop r00", "r01": "boom"}

    def stop(name):
        if answers.get(name) == "boom":
            raise RuntimeError("zenoh session closed")
        return answers[name]

    app = FleetApp(
        source=lambda p: m.view(W + now[0] - MONO, now[0], p, SESSION), opener=lambda a: 0, stop=stop
    )
    async with app.run_test(size=(300, 33)) as pilot:
        await pilot.pause()
        lst = app.screen.query_one(FleetList)
        app.screen.ask_stops(["r00", "r01"])
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert app.is_running  # a stopper that raised ended nothing
        assert "asking failed: RuntimeError('zenoh session closed')" in shown_row(app, "r01")
        assert lst.stops["r00"].failed and lst.stops["r01"].failed  # "not stopped: " is no success
        said = [n.message for n in app._notifications if "not stopped" in n.message]
        assert len(said) == 1 and "2 of 2 robots not stopped" in said[0], said  # one line for both
        now[0] += STOP_NOTE_S + 1
        for name in ("r00", "r01", "r02"):
            m.accept(status(name, t=W + STOP_NOTE_S + 1), 400, now[0])
        app.screen.sample()
        await pilot.pause()
        assert lst.stops == {}, lst.stops
        assert "not stopped" not in shown_row(app, "r00")


async def test_stop_all_shown_refused_everywhere_is_one_line_and_not_a_repaint_per_answer(monkeypatch):
    n = 30
    m = many(n)
    together = threading.Barrier(n, timeout=10)

    def refuse(name):
        together.wait()  # every answer comes at once, as a router's refusals do
        return f"not stopped: this console may not stop {name}"

    app = FleetApp(source=lambda p: m.view(W, MONO, p, SESSION), opener=lambda a: 0, stop=refuse)
    batches = []
    set_stops = FleetList.set_stops

    def counted(self, notes):
        batches.append(len(notes))
        set_stops(self, notes)

    monkeypatch.setattr(FleetList, "set_stops", counted)
    async with app.run_test(size=(200, 50)) as pilot:
        await pilot.press("S", "S")
        await app.workers.wait_for_complete()
        await pilot.pause()
        said = [x.message for x in app._notifications if "not stopped" in x.message]
        assert len(said) == 1 and f"{n} of {n} robots not stopped" in said[0], said  # before: one each
        assert batches[0] == n and sum(batches[1:]) == n and len(batches) - 1 < n / 2, batches
