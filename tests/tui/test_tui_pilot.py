"""Pilot tests: press the keys a user presses and check what reaches the link, the store and the files."""

import json
from pathlib import Path

import pytest

from arbiter_core.kinematics import Pose
from arbiter_tui.analytics.exports import CSV_HEADER
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.link.base import DISCONNECTED
from arbiter_tui.shell.screens.analytics import AnalyticsScreen
from arbiter_tui.shell.screens.confirm import ConfirmClear
from arbiter_tui.shell.screens.control import ControlScreen
from arbiter_tui.shell.screens.help import HelpScreen
from arbiter_tui.shell.screens.latency import LatencyScreen

from ..support.tui import SEEDED_POINTS, RecordingLink, still_app, until

SIZE = (100, 30)


async def test_teleop_keys_send_the_right_twists_and_stop_by_themselves():
    app = still_app()
    link = app.session.link
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        assert link.sent[-1] == (0.5, 0.0)  # sent on the press, not at the next tick
        app.fake_clock.t += 0.1  # a tick later: --repeat-rate (10 Hz) is a ceiling
        await pilot.press("comma")
        assert link.sent[-1] == (-0.5, 0.0)
        app.fake_clock.t += 0.1
        await pilot.press("u")
        assert link.sent[-1] == (0.5, 1.0)
        await pilot.press("q")  # scale both by 1.1 while moving
        app.session.tick_control()
        assert link.sent[-1] == pytest.approx((0.55, 1.1))
        app.fake_clock.t += 0.1
        await pilot.press("left")
        assert link.sent[-1] == pytest.approx((0.0, 1.1))
        # key timeout: repeats until the deadline, then exactly one zero, then silence
        n = len(link.sent)
        app.fake_clock.t += 0.3
        app.session.tick_control()
        assert link.sent[n:] == [pytest.approx((0.0, 1.1))]
        app.fake_clock.t += 0.5
        for _ in range(5):
            app.session.tick_control()
        assert link.sent[n + 1 :] == [(0.0, 0.0)]


async def test_space_and_k_stop_at_once():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        await pilot.press("space")
        app.session.tick_control()
        assert app.session.link.sent[-1] == (0.0, 0.0)
        await pilot.press("j")
        assert app.session.link.sent[-1] == (0.0, 1.0)
        await pilot.press("k")
        app.session.tick_control()
        assert app.session.link.sent[-1] == (0.0, 0.0)


async def test_leaving_the_control_screen_ends_a_held_key():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        await pilot.press("2")
        assert isinstance(app.screen, AnalyticsScreen)
        assert app.session.link.sent[-1] == (0.0, 0.0)
        assert app.session.stop_reason == "left the control screen"
        assert not app.session.teleop.moving


async def test_ctrl_c_stops_then_quits():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        await pilot.press("ctrl+c")
    assert app.session.link.sent[-1] == (0.0, 0.0)
    assert app.return_code in (0, None)


async def test_focus_loss_stops_the_robot():
    from textual import events

    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        app.post_message(events.AppBlur())
        await pilot.pause()
        assert app.session.link.sent[-1] == (0.0, 0.0)


async def test_nothing_is_sent_while_disconnected():
    link = RecordingLink(state=DISCONNECTED)
    app = still_app(link=link)
    async with app.run_test(size=SIZE) as pilot:
        for key in ("i", "i", "u"):
            await pilot.press(key)
            app.fake_clock.t += 0.1
        app.session.tick_control()
        assert link.sent == []
        assert app.session.loop.unsent >= 3
        assert "DISCONNECTED" in app.sampler.status().text()


async def test_screens_switch_and_keep_collected_data(tmp_path):
    store = AnalyticsStore()
    app = still_app(tmp_path, store=store)
    async with app.run_test(size=SIZE) as pilot:
        assert store.is_collecting  # recording is on from the start
        await pilot.press("2")
        await pilot.press("1")
        assert isinstance(app.screen, ControlScreen)
        for _ in range(7):
            app.session.loop.sample()
        await pilot.press("3")
        assert isinstance(app.screen, LatencyScreen)
        await pilot.press("2")
        assert len(store) == 7
        assert app.screen.query_one("#cards").render().plain.split()[1] == "7"
        await pilot.press("question_mark")
        assert isinstance(app.screen, HelpScreen)
        await pilot.press("escape")
        assert isinstance(app.screen, AnalyticsScreen)


async def test_export_chooser_writes_files_with_the_data(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    app = still_app(Path("."))  # a relative export directory, as the default "." is
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2", "ctrl+s", "c")
        await pilot.press("ctrl+s", "j")
        await pilot.press("ctrl+s", "m")
        await pilot.pause()
        assert isinstance(app.screen, AnalyticsScreen)  # the chooser closed each time
        written = [n.message for n in app._notifications if n.message.startswith("wrote")]
        assert len(written) == 3
        assert all(f"wrote {tmp_path.resolve()}/arbiter_analytics_" in m for m in written), written
    files = sorted(p.suffix for p in tmp_path.iterdir())
    assert files == [".csv", ".json", ".mcap"]
    csv_file = next(tmp_path.glob("arbiter_analytics_*.csv"))
    lines = csv_file.read_text().splitlines()
    assert lines[0] == CSV_HEADER and len(lines) == SEEDED_POINTS + 1
    doc = json.loads(next(tmp_path.glob("*.json")).read_text())
    assert doc["stats"]["sampleCount"] == SEEDED_POINTS
    assert app.session.last_export is not None and app.session.last_export.error is None


async def test_export_all_and_escape(tmp_path):
    app = still_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2", "ctrl+s", "escape")
        assert list(tmp_path.iterdir()) == []
        await pilot.press("ctrl+s", "a")
        await pilot.pause()
    assert sorted(p.suffix for p in tmp_path.iterdir()) == [".csv", ".json", ".mcap"]


async def test_export_failure_is_shown_and_data_kept(tmp_path):
    app = still_app(tmp_path / "missing")
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2", "ctrl+s", "c")
        await pilot.pause()
        assert app.session.last_export.error is not None
        assert len(app.session.store) == SEEDED_POINTS
        failed = [n for n in app._notifications if "EXPORT FAILED" in n.message]
        assert failed and "collected data kept" in failed[0].message and failed[0].severity == "error"


async def test_clearing_asks_first_and_keep_is_the_default(tmp_path):
    app = still_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2", "delete")
        assert isinstance(app.screen, ConfirmClear)
        await pilot.press("enter")  # the focused button keeps the data
        assert isinstance(app.screen, AnalyticsScreen) and len(app.session.store) == SEEDED_POINTS
        await pilot.press("delete", "n")
        assert len(app.session.store) == SEEDED_POINTS
        await pilot.press("delete", "y")
        await pilot.pause()
        assert len(app.session.store) == 0
        assert any(f"cleared {SEEDED_POINTS} samples" in n.message for n in app._notifications)


TELEOP_LETTERS = "uiojklm,.qzwxec"


@pytest.mark.parametrize("screen", ["1", "2", "3"])
async def test_no_teleop_letter_is_destructive_on_any_screen(tmp_path, screen):
    """Muscle memory from teleop_twist_keyboard must not lose data or write files anywhere."""
    app = still_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press(screen)
        kind = type(app.screen)
        keys = [("comma" if k == "," else "full_stop" if k == "." else k) for k in TELEOP_LETTERS]
        keys += [k.upper() for k in TELEOP_LETTERS if k.isalpha()]
        for key in keys:
            await pilot.press(key)
            assert type(app.screen) is kind, key  # no dialog, no screen change
        assert len(app.session.store) == SEEDED_POINTS and not app.session.store.is_collecting
        assert list(tmp_path.iterdir()) == []
        if screen != "1":  # off the control screen, movement letters move nothing
            assert all(cmd == (0.0, 0.0) for cmd in app.session.link.sent)


async def test_an_autonomous_run_keeps_driving_on_screens_2_and_3_and_space_stops_it_there():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("a", "g")
        for screen in ("2", "3"):
            await pilot.press(screen)
            n = len(app.session.link.sent)
            app.session.tick_control()
            assert app.session.loop.running and len(app.session.link.sent) == n + 1
            assert app.session.link.sent[-1] != (0.0, 0.0)
            await pilot.press("space")
            assert not app.session.loop.running and app.session.link.sent[-1] == (0.0, 0.0)
            assert app.session.stop_reason == "stop key"
            await pilot.press("1", "g")  # start again for the next screen
        await pilot.press("3", "k")  # k stops too
        assert not app.session.loop.running and app.session.link.sent[-1] == (0.0, 0.0)


async def test_a_terminal_too_small_stops_the_robot_and_ignores_movement_keys():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("a", "g")
        app.session.tick_control()
        assert app.session.loop.running
        await pilot.resize_terminal(60, 20)
        await pilot.pause()
        assert not app.session.loop.running and app.session.link.sent[-1] == (0.0, 0.0)
        assert app.session.stop_reason == "terminal too small"
        n = len(app.session.link.sent)
        await pilot.press("i", "i", "u", "g")
        app.session.tick_control()
        assert (
            app.session.link.sent[n:] == [] and not app.session.teleop.moving and not app.session.loop.running
        )
        await pilot.resize_terminal(*SIZE)
        await pilot.pause()
        await pilot.press("i")
        assert app.session.link.sent[-1] == (0.5, 0.0)  # back to normal once it fits


async def test_widgets_do_no_work_when_their_data_did_not_change():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        status_line, panel, live_map = (app.screen.query_one(q) for q in ("#status", "#robot", "#map"))
        before = (status_line.renders, panel.renders, live_map.draws)
        for _ in range(20):
            app.sample_frame()
            await pilot.pause()
        assert (status_line.renders, panel.renders, live_map.draws) == before  # nothing changed: no work
        app.session.link.telemetry.pose = Pose(1.26, -0.5, 0.6)  # a centimetre: the panel says so, the map's
        app.sample_frame()  # arrow stays in its cell and is not redrawn
        await pilot.pause()
        assert panel.renders > before[1] and live_map.draws == before[2]
        app.session.link.telemetry.pose = Pose(1.5, -0.5, 0.6)  # the robot moved by a cell and more
        app.sample_frame()
        await pilot.pause()
        assert status_line.renders == before[0]  # the status line did not change
        assert await until(pilot, lambda: app.sample_frame() or live_map.draws > before[2], timeout=2)


async def test_autonomous_controller_sends_commands_and_manual_keys_take_over():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("a")
        assert app.session.loop.algorithm == "go_to_goal"
        await pilot.press("g")
        app.session.tick_control()
        v, w = app.session.link.sent[-1]
        assert v >= 0 and (v, w) != (0.0, 0.0)
        await pilot.press("i")
        assert app.session.loop.algorithm == "manual" and not app.session.loop.running
        assert app.session.link.sent[-1] == (0.5, 0.0)


async def test_one_store_per_session_outlives_screen_switches():
    """The seed's singleton, scoped to the robot session: every screen shares it, another session
    (another robot, another test) has its own; no module-level store."""
    from arbiter_tui.session.settings import Settings
    from arbiter_tui.shell.app import make_app

    app = make_app(Settings(live=False, handle_signals=False), RecordingLink())
    other = make_app(Settings(live=False, handle_signals=False), RecordingLink())
    assert app.session.store is app.session.store and other.session.store is not app.session.store
    async with app.run_test(size=(100, 30)) as pilot:
        store = app.session.store
        for key in ("2", "3", "1", "2"):
            await pilot.press(key)
            assert app.session.store is store


async def test_the_first_frame_comes_before_the_link_and_the_link_is_attached_when_ready():
    import threading

    from arbiter_tui.session.settings import Settings
    from arbiter_tui.shell.app import make_app

    release = threading.Event()
    link = RecordingLink()
    closed = []

    def connector():
        release.wait(10)  # the embedded backend taking its time to start
        return link, None, lambda: closed.append(True)

    settings = Settings(handle_signals=False, transport="ros")
    app = make_app(settings, store=AnalyticsStore(), connector=connector)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        status = app.screen.query_one("#status").render().plain
        assert status.startswith("STARTING · embedded ros"), status
        await pilot.press("i")
        assert link.sent == []  # nothing is sent before the link exists
        release.set()
        assert await until(pilot, lambda: app.session.link is link)
        await pilot.press("i")
        assert link.sent[-1] == (0.5, 0.0)
        assert await until(pilot, lambda: "CONNECTED · embedded ros 9090/8085" in app.sampler.status().text())
    app.close_link()
    assert closed == [True]


async def test_a_backend_that_cannot_start_is_said_on_screen():
    from arbiter_tui.session.settings import Settings
    from arbiter_tui.shell.app import make_app

    def connector():
        raise RuntimeError("the bundled backend exited: address already in use")

    app = make_app(Settings(handle_signals=False), store=AnalyticsStore(), connector=connector)
    async with app.run_test(size=SIZE) as pilot:
        assert await until(pilot, lambda: app.sampler.start_error is not None)
        await pilot.pause()
        status = app.screen.query_one("#status")
        assert "address already in use" in status.render().plain and status.has_class("alarm")
        assert app.is_running  # still at the console: quit with ctrl+q


async def test_a_theme_chosen_in_the_console_is_kept_in_the_config_file(tmp_path):
    from arbiter_tui.session.settings import Settings
    from arbiter_tui.shell.app import make_app

    path = tmp_path / "config.toml"
    path.write_text("speed = 0.3\n")
    settings = Settings(live=False, handle_signals=False, config_path=path, theme="nord")
    app = make_app(settings, RecordingLink(), store=AnalyticsStore())
    async with app.run_test(size=SIZE) as pilot:
        assert app.theme == "nord"  # from the file
        assert path.read_text() == "speed = 0.3\n"  # loading it wrote nothing
        app.theme = "dracula"  # as the palette's theme picker does
        await pilot.pause()
    assert path.read_text() == 'theme = "dracula"\nspeed = 0.3\n'


async def test_a_poller_that_asks_what_is_shown_while_the_app_exits_gets_an_answer():
    """The topics poller asks what is shown on its own schedule; at exit the screen stack is empty (CI
    once saw ``ScreenStackError('No screens on stack')`` fail the worker, and the app, at quit)."""
    from arbiter_tui.shell.app import _screens, _shown

    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2")
        assert _shown(app).screen == "analytics" and _screens(app)
    assert _screens(app) == []  # exited: no screens, no exception
    assert not _shown(app).shows("topics")
