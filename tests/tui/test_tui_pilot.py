"""Pilot tests: press the keys a user presses and check what reaches the link, the store and the files."""

import json

import pytest

from arbiter_tui.analytics.exports import CSV_HEADER
from arbiter_tui.analytics.store import STORE, AnalyticsStore
from arbiter_tui.link.base import DISCONNECTED
from arbiter_tui.screens.analytics import AnalyticsScreen
from arbiter_tui.screens.control import ControlScreen
from arbiter_tui.screens.help import HelpScreen
from arbiter_tui.screens.latency import LatencyScreen

from ..support.tui import RecordingLink, still_app

SIZE = (100, 30)


async def test_teleop_keys_send_the_right_twists_and_stop_by_themselves():
    app = still_app()
    link = app.link
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        assert link.sent[-1] == (0.5, 0.0)  # sent on the press, not at the next tick
        await pilot.press("comma")
        assert link.sent[-1] == (-0.5, 0.0)
        await pilot.press("u")
        assert link.sent[-1] == (0.5, 1.0)
        await pilot.press("q")  # scale both by 1.1 while moving
        app._control_tick()
        assert link.sent[-1] == pytest.approx((0.55, 1.1))
        await pilot.press("left")
        assert link.sent[-1] == pytest.approx((0.0, 1.1))
        # key timeout: repeats until the deadline, then exactly one zero, then silence
        n = len(link.sent)
        app.fake_clock.t += 0.3
        app._control_tick()
        assert link.sent[n:] == [pytest.approx((0.0, 1.1))]
        app.fake_clock.t += 0.5
        for _ in range(5):
            app._control_tick()
        assert link.sent[n + 1 :] == [(0.0, 0.0)]


async def test_space_and_k_stop_at_once():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        await pilot.press("space")
        app._control_tick()
        assert app.link.sent[-1] == (0.0, 0.0)
        await pilot.press("j")
        assert app.link.sent[-1] == (0.0, 1.0)
        await pilot.press("k")
        app._control_tick()
        assert app.link.sent[-1] == (0.0, 0.0)


async def test_leaving_the_control_screen_stops_the_robot():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        await pilot.press("2")
        assert isinstance(app.screen, AnalyticsScreen)
        assert app.link.sent[-1] == (0.0, 0.0)
        assert app.stop_reason == "left the control screen"
        assert not app.teleop.moving


async def test_ctrl_c_stops_then_quits():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        await pilot.press("ctrl+c")
    assert app.link.sent[-1] == (0.0, 0.0)
    assert app.return_code in (0, None)


async def test_focus_loss_stops_the_robot():
    from textual import events

    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i")
        app.post_message(events.AppBlur())
        await pilot.pause()
        assert app.link.sent[-1] == (0.0, 0.0)


async def test_nothing_is_sent_while_disconnected():
    link = RecordingLink(state=DISCONNECTED)
    app = still_app(link=link)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("i", "i", "u")
        app._control_tick()
        assert link.sent == []
        assert app.loop.unsent >= 3
        assert "DISCONNECTED" in app.status_text()


async def test_screens_switch_and_keep_collected_data(tmp_path):
    store = AnalyticsStore()
    app = still_app(tmp_path, store=store)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2", "r")
        assert store.is_collecting
        await pilot.press("1")
        assert isinstance(app.screen, ControlScreen)
        for _ in range(7):
            app.loop.sample()
        await pilot.press("3")
        assert isinstance(app.screen, LatencyScreen)
        await pilot.press("2")
        assert len(store) == 7
        assert app.screen.query_one("#cards").render().plain.split()[1] == "7"
        await pilot.press("question_mark")
        assert isinstance(app.screen, HelpScreen)
        await pilot.press("escape")
        assert isinstance(app.screen, AnalyticsScreen)


async def test_export_keys_write_files_with_the_data(tmp_path):
    app = still_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2", "c", "j", "m")
    files = sorted(p.suffix for p in tmp_path.iterdir())
    assert files == [".csv", ".json", ".mcap"]
    csv_file = next(tmp_path.glob("arbiter_analytics_*.csv"))
    lines = csv_file.read_text().splitlines()
    assert lines[0] == CSV_HEADER and len(lines) == 121
    doc = json.loads(next(tmp_path.glob("*.json")).read_text())
    assert doc["stats"]["sampleCount"] == 120
    assert "wrote" in app.export_message


async def test_export_failure_is_shown_and_data_kept(tmp_path):
    app = still_app(tmp_path / "missing")
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2", "c")
        assert "EXPORT FAILED" in app.export_message
        assert len(app.store) == 120
        assert "EXPORT FAILED" in str(app.screen.query_one("#export-msg").render())


async def test_autonomous_controller_sends_commands_and_manual_keys_take_over():
    app = still_app()
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("a")
        assert app.loop.algorithm == "go_to_goal"
        await pilot.press("g")
        app._control_tick()
        v, w = app.link.sent[-1]
        assert v >= 0 and (v, w) != (0.0, 0.0)
        await pilot.press("i")
        assert app.loop.algorithm == "manual" and not app.loop.running
        assert app.link.sent[-1] == (0.5, 0.0)


def test_default_store_is_the_singleton():
    from arbiter_tui.app import make_app
    from arbiter_tui.settings import Settings

    app = make_app(Settings(live=False, handle_signals=False), RecordingLink())
    assert app.store is STORE
