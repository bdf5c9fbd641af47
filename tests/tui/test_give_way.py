"""Paints give way to the control ticks only where the console has no core to spare: a live app over
the simulated link (its ticks on the session's thread), the core count given."""

import pytest

from arbiter_tui.link.sim import SimLink
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell import lifecycle
from arbiter_tui.shell.app import make_app
from arbiter_tui.shell.perf import give_way

from ..support.tui import until


@pytest.mark.parametrize("cores", [0.25, 4.0])
async def test_paints_wait_for_a_due_tick_only_without_a_core_to_spare(monkeypatch, tmp_path, cores):
    monkeypatch.setattr(lifecycle, "cores_available", lambda: cores)
    # a guard of most of a period: frames start just after a tick, and a fast machine paints them
    # long before the next one (the 10 ms guard is for a paint that runs late, on a slow one)
    monkeypatch.setattr(give_way, "GUARD_S", 0.09)
    app = make_app(Settings(mode="sim", live=True, handle_signals=False, export_dir=tmp_path), SimLink())
    async with app.run_test(size=(200, 60)) as pilot:  # the dashboard: many widgets a paint
        await pilot.press("a", "g")  # a mission: the map and the panel repaint at every frame
        assert await until(pilot, lambda: app.session.schedule.ticks_written > 30, timeout=20)
        if cores < 2:
            assert await until(pilot, lambda: app.session.schedule.gave_way > 0, timeout=20)
        else:
            assert app.session.schedule.gave_way == 0 and give_way._hook is None
    assert give_way._hook is None  # the app gone, nothing is asked any more
