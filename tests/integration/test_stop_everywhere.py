"""The stop matrix (issue 46): on every screen, with every dialog, the palette and every text input open,
in every way the robot can be driven -- manual keys held, a console mission, observe mode with the
robot-side controller, observe mode with a foreign controller behind an action server named as Nav2's --
the documented stop key (space or k where they are not text, ctrl+k where they are) makes the console's
commanded velocity zero at once (no control tick waited for) and the robot stand within 1 s.

Real processes and protocols throughout: an ``arbiter-backend --autonomy`` on loopback, the console's
RosLink (roslibpy) and tracker client (httpx), Pilot pressing the keys, a roslibpy node standing in for
Nav2 (tests/support/foreign.py). One app per way of driving; the contexts run one after another in it.
"""

import time
from collections.abc import Callable

import pytest
from textual.command import CommandPalette
from textual.widgets import Input

from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell.app import make_app
from arbiter_tui.shell.screens.confirm import ConfirmClear
from arbiter_tui.shell.screens.export import ExportChooser
from arbiter_tui.shell.screens.goal import GoalPrompt
from arbiter_tui.shell.screens.help import HelpScreen
from arbiter_tui.shell.screens.open_file import OpenRecording

from ..support.backend import start_backend
from ..support.foreign import FakeNav2
from ..support.tui import until

SIZE = (100, 30)
STAND_S = 1.0  # the robot stands this soon after the stop key
MOVING = 0.1  # m/s of odometry: the robot drives
STILL = 0.01

# (screen key, what is opened over it, how, the stop key pressed there)
CONTEXTS = [
    ("1", None, (), "space"),
    ("1", HelpScreen, ("question_mark",), "k"),
    ("1", CommandPalette, ("ctrl+p",), "ctrl+k"),
    ("1", GoalPrompt, ("t",), "ctrl+k"),
    ("2", None, (), "k"),
    ("2", HelpScreen, ("question_mark",), "space"),
    ("2", CommandPalette, ("ctrl+p",), "ctrl+k"),
    ("2", ExportChooser, ("ctrl+s",), "space"),
    ("2", ConfirmClear, ("delete",), "k"),
    ("2", OpenRecording, ("f",), "ctrl+k"),  # a path: space and k are text there
    ("3", None, (), "space"),
    ("3", HelpScreen, ("question_mark",), "ctrl+k"),
    ("3", CommandPalette, ("ctrl+p",), "ctrl+k"),
    ("4", None, (), "k"),
    ("4", HelpScreen, ("question_mark",), "space"),
    ("4", CommandPalette, ("ctrl+p",), "ctrl+k"),
    ("4", Input, ("slash",), "ctrl+k"),  # the topics filter: space and k are text there
]


@pytest.fixture(scope="module")
def backend():
    proc = start_backend("--autonomy")
    yield proc
    proc.stop()


def opened(app, overlay) -> bool:
    if overlay is None:
        return True
    if overlay is Input:
        return isinstance(app.focused, Input)
    return isinstance(app.screen, overlay)


async def close_overlay(pilot, app, overlay) -> None:
    if overlay is None:
        return
    await pilot.press("escape")
    assert await until(pilot, lambda: not opened(app, overlay), timeout=5)


async def run_matrix(app, link, pilot, start: Callable, stopped: Callable, contexts=CONTEXTS) -> list[str]:
    """For each context: drive (``start``), open the context, press its stop key; ``stopped(t0)`` checks
    what the stop did. Returns the per-context timings, for the failure message."""
    said = []
    for screen, overlay, opening, key in contexts:
        if overlay is GoalPrompt and app.settings.observe:
            continue  # observe mode types no goals (t is not offered)
        await pilot.press("1")
        await start(pilot)
        assert await until(pilot, lambda: abs(link.telemetry.v) > MOVING, timeout=10), (screen, overlay)
        if screen != "1":
            await pilot.press(screen)
        for k in opening:
            await pilot.press(k)
        assert await until(pilot, lambda o=overlay: opened(app, o), timeout=5), (screen, overlay)
        if screen == "1" and overlay is None:
            assert abs(link.telemetry.v) > MOVING  # still driving when the key comes
        t0 = time.monotonic()
        await pilot.press(key)
        # the console's own command is zero at once: the stop sent it, no control tick waited for
        loop = app.session.loop
        assert loop.command == (0.0, 0.0) and not loop.running, (screen, overlay, key)
        assert not app.session.teleop.moving
        stood = await until(pilot, lambda: max(abs(link.telemetry.v), abs(link.telemetry.w)) < STILL, 10)
        took = time.monotonic() - t0
        said.append(f"{screen}/{getattr(overlay, '__name__', '-')}/{key}: {took:.2f} s")
        assert stood and took <= STAND_S, (screen, overlay, key, said)
        await stopped(pilot, t0)
        if overlay is Input:
            assert app.focused.value == "", "ctrl+k stopped the robot and typed nothing"
        await close_overlay(pilot, app, overlay)
    return said


def console_app(backend, tmp_path, **settings):
    link = RosLink("127.0.0.1", backend.bridge_port)
    tracker = TrackerClient(backend.api)
    s = Settings(handle_signals=False, export_dir=tmp_path, **settings)
    return make_app(s, link, tracker), link


async def no_remote(pilot, t0) -> None:
    return None


async def test_a_mission_stops_from_every_screen_dialog_and_input(backend, tmp_path):
    app, link = console_app(backend, tmp_path)
    try:
        async with app.run_test(size=SIZE) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 15)
            app.session.select_algorithm("stanley")
            app.session.select_mission("corner")  # a long straight: it drives in every context

            async def start(pilot):
                await pilot.press("g")
                assert app.session.loop.running

            said = await run_matrix(app, link, pilot, start, no_remote)
            assert len(said) == len(CONTEXTS)
    finally:
        link.close()


async def test_held_keys_stop_from_every_screen_dialog_and_input(backend, tmp_path):
    app, link = console_app(backend, tmp_path)
    try:
        async with app.run_test(size=SIZE) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 15)

            async def start(pilot):
                for _ in range(4):  # held: auto-repeat inside the key timeout
                    await pilot.press("i")
                    await pilot.pause(0.05)

            said = await run_matrix(app, link, pilot, start, no_remote)
            assert len(said) == len(CONTEXTS)
    finally:
        link.close()


def observe_app(backend, tmp_path):
    return console_app(
        backend, tmp_path, observe=True, observe_label="observed", cmd_topic="/cmd_vel_measured"
    )


async def test_observe_mode_stops_the_robot_side_controller_from_everywhere(backend, tmp_path):
    app, link = observe_app(backend, tmp_path)
    autonomy = app.session.autonomy
    try:
        async with app.run_test(size=SIZE) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 15)
            # the panel learns the backend runs one: a, n and g are offered
            side = lambda: app.sampler.robot_side  # noqa: E731
            assert await until(pilot, lambda: side() is not None and side().enabled)
            # the status line names what drives: the robot-side stanley, not the console's "manual"
            autonomy.start("stanley", "corner", 0.5, 1.0)
            status = lambda: app.sampler.frame.status.text()  # noqa: E731
            assert await until(pilot, lambda: "robot-side stanley" in status(), timeout=10), status()

            async def start(pilot):
                app.session.remote_stop.wait_idle(5)  # the last stop's zeros are over
                autonomy.start("stanley", "corner", 0.5, 1.0)

            async def stopped(pilot, t0):
                assert await until(pilot, lambda: app.session.remote_stop.wait_idle(0) and bool(
                    app.session.remote_stop.reports), timeout=10)  # fmt: skip
                report = app.session.remote_stop.reports[-1]
                assert report.robot_side is not None and report.robot_side.stopped, report
                assert autonomy.status().state == "aborted"
                assert "stopped the robot-side stanley on corner" in report.text()

            said = await run_matrix(app, link, pilot, start, stopped)
            assert len(said) == len(CONTEXTS) - 1
    finally:
        link.close()


async def test_observe_mode_cancels_a_foreign_action_servers_goals_from_everywhere(backend, tmp_path):
    app, link = observe_app(backend, tmp_path)
    nav2 = FakeNav2(backend.bridge_port, "/cmd_vel_measured")
    try:
        async with app.run_test(size=SIZE) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 15)

            async def start(pilot):
                app.session.remote_stop.wait_idle(5)
                nav2.start_goal(0.3)

            async def stopped(pilot, t0):
                assert await until(pilot, lambda: app.session.remote_stop.wait_idle(0) and bool(
                    app.session.remote_stop.reports), timeout=10)  # fmt: skip
                report = app.session.remote_stop.reports[-1]
                assert not nav2.active and nav2.cancels, "the goal was cancelled through rosbridge"
                assert "cancelled 1 goal of /navigate_to_pose" in report.text(), (report.text(), nav2.cancels)
                assert "zero velocity on /cmd_vel_measured for 1 s" in report.text()
                assert not report.unsure

            said = await run_matrix(app, link, pilot, start, stopped)
            assert len(said) == len(CONTEXTS) - 1
    finally:
        nav2.close()
        link.close()


async def test_a_foreign_controller_with_no_action_server_is_said_not_stopped(backend, tmp_path):
    """Zero velocity is all a console can send a controller with no action server: it says so, and that a
    controller still publishing overrides it (the robot drives on: the console cannot stop it)."""
    app, link = observe_app(backend, tmp_path)
    rogue = FakeNav2(backend.bridge_port, "/cmd_vel_measured", cancellable=False)
    try:
        async with app.run_test(size=SIZE) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 15)
            rogue.start_goal(0.3)
            assert await until(pilot, lambda: abs(link.telemetry.v) > MOVING, timeout=10)
            await pilot.press("space")
            assert app.session.remote_stop.wait_idle(10)
            text = app.session.remote_stop.reports[-1].text()
            assert "no action server on /navigate_to_pose, /navigate_through_poses and 6 more" in text, text
            assert "sent zero velocity on /cmd_vel_measured for 1 s only: a controller still publishing " \
                   "will override it" in text  # fmt: skip
            assert await until(pilot, lambda: text in {str(n.message) for n in app._notifications})
            assert rogue.active and abs(link.telemetry.v) > MOVING  # said, not hidden: it still drives
    finally:
        rogue.close()
        link.close()
