"""The fleet screen (arbiter_tui.fleet.app): snapshots at 80x24 and 200x60 with live, stale, lost and bad-data
rows, and the keys a user presses (Pilot): severity order, the name filter, Enter opening the single-robot
console on the advertised URLs and coming back, a lost robot not opened, the history on ``h``."""

import time

import pytest
from textual.widgets import Static

from arbiter_core import fleet
from arbiter_core.timesync import TimeSync
from arbiter_tui.fleet.app import FleetApp, FleetList
from arbiter_tui.fleet.rows import FleetModel, detail_lines

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


def fleet_app(opened=None, history=None, pattern=""):
    model = fleet_model()
    calls = [] if opened is None else opened

    def opener(argv):
        calls.append(argv)
        return 0

    return FleetApp(
        source=lambda p: model.view(W, MONO, p, SESSION), opener=opener, history=history, pattern=pattern
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


async def test_a_view_that_shows_the_same_text_repaints_nothing(monkeypatch):
    """Views come twice a second, each with its own clock; the list repaints only when a row's text
    changed (an age shown in whole seconds), and the header and detail are not laid out again."""
    model, clock = fleet_model(), [0.0]
    renders, updates = [0], [0]
    real_render, real_update = FleetList.render, Static.update

    def render(self):
        renders[0] += 1
        return real_render(self)

    def update(self, *args, **kwargs):
        updates[0] += 1
        return real_update(self, *args, **kwargs)

    monkeypatch.setattr(FleetList, "render", render)
    monkeypatch.setattr(Static, "update", update)
    app = FleetApp(source=lambda p: model.view(W + clock[0], MONO + clock[0], p, SESSION), opener=lambda a: 0)
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.pause()
        before = renders[0], updates[0]
        for _ in range(3):  # 0.1 s later each time: every age shown is the same whole second
            clock[0] += 0.1
            app.screen.sample()
            await pilot.pause()
        assert (renders[0], updates[0]) == before
        clock[0] += 1.0  # the ages shown move on
        app.screen.sample()
        await pilot.pause()
        assert renders[0] > before[0]


async def test_at_80_columns_the_head_and_every_detail_line_are_whole():
    """Issue 54, item 7: at 80 columns the head's "connecting: client of ..." and the detail's longer
    lines were cut (an ellipsis, the rest lost): now each breaks between its parts, then indented."""
    from rich.cells import cell_len

    model = fleet_model()
    session = "connecting: client of tcp/192.168.100.200:7447,tcp/192.168.100.201:7447"
    app = FleetApp(source=lambda p: model.view(W, MONO, p, session), opener=lambda argv: 0)
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
            head = " ".join(str(app.screen.query_one("#fleet-head", Static).render()).split())
            assert head.startswith("fleet · 2 of 8 robots") and session in head, head
            detail = str(app.screen.query_one("#fleet-detail", Static).render())
            row = rows.current()
            words = lambda text: " ".join(w for w in text.split() if w != "·")  # noqa: E731
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
