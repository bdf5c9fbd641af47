"""The analytics screen's sweep on a console with no core to spare: held while a mission drives, and
said so on screen; it goes on, and its curve shows, once the robot stands still. A live app over the
simulated link (its control ticks on the session's thread) and a real child process."""

from arbiter_tui.analytics.linkcurve import READY, RUNNING
from arbiter_tui.link.sim import SimLink
from arbiter_tui.session import link_sweep
from arbiter_tui.session.link_sweep import SweepPause
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell.app import make_app
from arbiter_tui.shell.screens.analytics import AnalyticsScreen

from ..integration.test_link_sweep import BODY, cpu_bound_child, state
from ..support.tui import until


async def test_a_mission_holds_the_sweep_and_the_screen_says_so(monkeypatch, tmp_path):
    monkeypatch.setattr(link_sweep, "command", lambda m, s, t: cpu_bound_child(0.3, BODY))
    pids: list[int] = []
    pause = SweepPause(lambda: 0.25)  # a Pi stand-in's quota, whatever this machine has
    real_child = pause.child
    pause.child = lambda pid: (pids.append(pid), real_child(pid))
    app = make_app(Settings(mode="sim", live=True, handle_signals=False, export_dir=tmp_path), SimLink())
    app.sampler.sweep_pause = pause
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("a", "g")  # a controller (the first after manual) drives the selected mission
        assert await until(pilot, lambda: app.session.schedule.driving)
        await pilot.press("2")
        assert isinstance(app.screen, AnalyticsScreen)
        line = app.screen.query_one("#link-line")
        assert await until(pilot, lambda: app.frame.link_sweep.paused)
        assert app.frame.link_sweep.state == RUNNING and state(pids[0]) == "T"
        assert await until(pilot, lambda: "paused while the robot drives" in str(line.render()))
        await pilot.press("space")  # stop: the sweep goes on a second later and its curve shows
        assert await until(pilot, lambda: app.frame.link_sweep.state == READY, timeout=15)
        assert app.frame.link_sweep.curve is not None and not app.frame.link_sweep.paused
        assert await until(pilot, lambda: "paused" not in str(line.render()))
