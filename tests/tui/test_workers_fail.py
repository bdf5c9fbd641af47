"""Every worker that can fail says so in the state it owns, whatever the failure (issue 54, items 11-12):
the analytics screen's latency sweep ends FAILED (never left running, so never started again) and is tried
again; the robot-side controller's start and a recording's reading say an unexpected failure, and work
the next time; what a worker's thread learns reaches the frame sampler (not thread-safe) on the UI's
thread only. Failures are injected where the work is done (``RuntimeError``, no failure the code expects)."""

import asyncio
import threading

from arbiter_tui.analytics.exports import to_json
from arbiter_tui.analytics.linkcurve import FAILED, RUNNING
from arbiter_tui.latency.autonomy import RobotSideView
from arbiter_tui.link.sim import SimLink
from arbiter_tui.session import frames
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell import dialogs, sweep
from arbiter_tui.shell.app import make_app

from ..support.points import random_points
from ..support.tui import still_app, until

SIZE = (100, 30)


def notices(app, word: str) -> list[str]:
    return [str(n.message) for n in app._notifications if word in str(n.message)]


async def test_a_sweep_that_fails_unexpectedly_ends_failed_and_is_tried_again(monkeypatch, tmp_path):
    calls: list[str] = []
    hold = asyncio.Event()

    async def sweep_curve(mission, speed, turn, pause=None):
        calls.append(mission)
        if len(calls) == 1:
            raise RuntimeError("a fault of ours")
        await hold.wait()  # the second sweep runs (until the app quits)

    monkeypatch.setattr(sweep, "sweep_curve", sweep_curve)
    app = make_app(Settings(mode="sim", live=True, handle_signals=False, export_dir=tmp_path), SimLink())
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2")
        assert await until(pilot, lambda: app.frame.link_sweep.state == FAILED)
        assert app.frame.link_sweep.error == "RuntimeError: a fault of ours"
        line = app.screen.query_one("#link-line")
        assert await until(pilot, lambda: "latency sweep failed: RuntimeError" in str(line.render()))
        assert await until(pilot, lambda: notices(app, "latency sweep failed: RuntimeError"))
        await pilot.pause(0.5)
        assert calls == ["square"] and app.frame.link_sweep.state == FAILED  # not at every frame
        monkeypatch.setattr(frames, "SWEEP_RETRY_S", 0.0)  # ... but once its retry time has come
        assert await until(pilot, lambda: len(calls) == 2)
        assert app.frame.link_sweep.state == RUNNING


async def test_the_robot_side_start_says_an_unexpected_failure_and_the_sampler_stays_on_the_ui_thread(
    tmp_path,
):
    app = still_app(tmp_path, observe=True, observe_label="observed", cmd_topic="/cmd_vel_measured")
    session, sampler = app.session, app.sampler
    touched: list[str] = []
    polled = sampler.robot_side_polled

    def robot_side_polled(view):
        touched.append(threading.current_thread().name)
        polled(view)

    sampler.robot_side_polled = robot_side_polled

    def broken():
        raise RuntimeError("the answer had no state")

    session.start_robot_side = broken
    async with app.run_test(size=SIZE) as pilot:
        sampler.robot_side_polled(RobotSideView(known=True, enabled=True, text="idle"))
        app.refresh_frame(force=True)
        app.screen.refresh_bindings()
        await pilot.press("g")
        assert await until(pilot, lambda: notices(app, "robot-side controller: RuntimeError"))
        session.start_robot_side = lambda: "robot-side go_to_goal on square: started on the robot"
        session.robot_side = lambda: RobotSideView(known=True, enabled=True, running=True, text="running")
        await pilot.press("g")  # it can be started again
        assert await until(pilot, lambda: notices(app, "started on the robot"))
        assert sampler.robot_side.running
        assert set(touched) == {threading.main_thread().name}, touched


async def test_a_recording_that_fails_unexpectedly_is_said_and_the_next_opens(monkeypatch, tmp_path):
    good = tmp_path / "export.json"
    good.write_text(to_json(random_points(30, seed=3)))
    real = dialogs.open_recording

    def broken(path):
        raise RuntimeError("a reader's fault")

    monkeypatch.setattr(dialogs, "open_recording", broken)
    app = still_app(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("2", "f", *str(good), "enter")
        assert await until(pilot, lambda: notices(app, "cannot open"), timeout=15)
        (said,) = notices(app, "cannot open")
        assert said == f"cannot open {good}: RuntimeError: a reader's fault"
        assert not app.frame.analytics.source  # the live session stays
        monkeypatch.setattr(dialogs, "open_recording", real)
        await pilot.press("f", *str(good), "enter")
        assert await until(pilot, lambda: bool(app.frame.analytics.source), timeout=15)


async def test_a_hang_up_arms_the_exit_deadline_before_it_finishes_the_journal(tmp_path, monkeypatch):
    """Finishing the journal may wait on a stalled disk: the process must be sure to end first."""
    import signal

    from arbiter_tui.shell import app as app_module

    order: list[str] = []
    monkeypatch.setattr(app_module.lifecycle, "exit_within", lambda s: order.append("deadline"))
    app = still_app(tmp_path)
    monkeypatch.setattr(app.session, "hang_up", lambda reason: order.append("hang up"))
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        app._on_signal(signal.SIGHUP)
    assert order == ["deadline", "hang up"]
