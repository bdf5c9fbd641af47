"""A stop is also what happens when the console loses its terminal, its link or its process (issue 46,
item 1): proven for a mission the console drives and for the console's own keys in observe mode (manual
driving: tests/integration/test_tmux.py). The robot is watched from outside, through a link of the
test's own to the same backend: it stands within 1 s.

What a console that goes away does *not* stop, by design: a robot-side or foreign controller it only
observes (README, "Safety"): that one runs on the robot and does not need the console."""

import subprocess
import time

import pytest

from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED, DISCONNECTED, RECONNECTING
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.settings import CONNECT, Settings
from arbiter_tui.shell.app import make_app

from ..support.backend import start_backend
from ..support.netfault import FaultProxy
from ..support.tui import until
from ..support.waits import wait_for
from .test_tmux import _alive, _tui_pid, launch_tui, screen_until, tmux

STAND_S = 1.0


def stands_within(link: RosLink, seconds: float) -> float | None:
    """How long until the robot's odometry says it stands (None: not within ``seconds`` x 5)."""
    t0 = time.monotonic()
    if wait_for(lambda: max(abs(link.telemetry.v), abs(link.telemetry.w)) < 0.01, seconds * 5, 0.01):
        return time.monotonic() - t0
    return None


@pytest.fixture
def watched():
    backend = start_backend()
    eye = RosLink("127.0.0.1", backend.bridge_port)  # the test's own view of the robot
    assert wait_for(lambda: eye.state == CONNECTED and eye.telemetry.odom_count > 0, 15)
    yield backend, eye
    eye.close()
    backend.stop()


@pytest.mark.parametrize("how", ["kill-session", "kill -9"])
@pytest.mark.parametrize("driving", ["mission", "observe, keys held"])
def test_a_console_that_loses_its_terminal_or_its_process_leaves_the_robot_standing(
    tmp_path, watched, how, driving
):
    backend, eye = watched
    observe = "--observe --label watched --cmd-topic /cmd_vel_measured " if driving != "mission" else ""
    args = (
        f"--connect --rosbridge ws://127.0.0.1:{backend.bridge_port} --tracker {backend.api} "
        f"--key-timeout 2 {observe}--export-dir {tmp_path}"
    )
    session, _done = launch_tui(tmp_path, args, linger=True)
    try:
        screen_until(session, "CONNECTED")
        pid = _tui_pid(session)
        if driving == "mission":
            tmux("send-keys", "-t", session, "a")
            screen_until(session, "go_to_goal")
            tmux("send-keys", "-t", session, "g")
            screen_until(session, "(driving)")
        else:
            screen_until(session, "OBSERVING watched")
            for _ in range(4):
                tmux("send-keys", "-t", session, "i")
                time.sleep(0.1)
            screen_until(session, "keys: teleop")
        assert wait_for(lambda: eye.telemetry.v > 0.1, 10), "the robot drives"
        if how == "kill-session":
            tmux("kill-session", "-t", session)  # SIGHUP and the terminal gone at once
        else:
            subprocess.run(["kill", "-9", str(pid)], check=True)  # no goodbye: the deadman's turn
        took = stands_within(eye, STAND_S)
        assert took is not None and took <= STAND_S, (how, driving, took)
        assert wait_for(lambda: not _alive(pid), 5)
    finally:
        tmux("kill-session", "-t", session)


async def test_a_mission_whose_link_dies_silently_leaves_the_robot_standing_and_is_forgotten(
    tmp_path, watched
):
    """A pulled cable (no FIN): the tracker's deadman stops the robot; the console notices the silent link
    (pings), the mission ends, and after the link returns nothing moves and g starts afresh."""
    backend, eye = watched
    proxy = FaultProxy(backend.bridge_port)
    link = RosLink("127.0.0.1", proxy.port)
    app = make_app(Settings(mode=CONNECT, handle_signals=False, export_dir=tmp_path), link,
                   TrackerClient(backend.api))  # fmt: skip
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 15)
            app.session.select_algorithm("stanley")
            app.session.select_mission("corner")
            await pilot.press("g")
            assert await until(pilot, lambda: eye.telemetry.v > 0.1, timeout=10)
            proxy.freeze()
            t0 = time.monotonic()
            assert await until(pilot, lambda: max(abs(eye.telemetry.v), abs(eye.telemetry.w)) < 0.01, 5)
            assert time.monotonic() - t0 <= STAND_S + 0.5  # the deadman's 0.5 s, then the next odometry
            assert await until(pilot, lambda: link.state in (DISCONNECTED, RECONNECTING), timeout=10)
            assert await until(pilot, lambda: not app.session.loop.running, timeout=5)
            proxy.thaw()
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=15)
            await pilot.pause(0.5)
            assert max(abs(eye.telemetry.v), abs(eye.telemetry.w)) < 0.01, "nothing moves after the return"
            assert app.session.loop.interrupted is None
    finally:
        link.close()
        proxy.close()
