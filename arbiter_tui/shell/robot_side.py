"""Observe mode's robot-side controller, from the console: asked how it is once a second (the panel
says it, and the footer offers a, n and g only where the backend runs one), and started by ``g`` on the
selected controller and mission. The requests run on worker threads (``RobotSession.robot_side`` and
``start_robot_side`` block on the backend's API)."""

from __future__ import annotations

import asyncio
import contextlib
from functools import partial
from typing import TYPE_CHECKING

from ..latency.autonomy import AutonomyUnavailable, RobotSideView
from ..session.pollers import poll_forever

if TYPE_CHECKING:
    from .app import ArbiterApp

PERIOD_S = 1.0
NO_GOALS = "observe mode: the console drives no goal here (g starts the robot-side controller)"


def poll(app: ArbiterApp) -> None:
    """Ask the robot-side controller how it is every ``PERIOD_S`` while the app runs."""

    async def ask() -> RobotSideView:
        return await asyncio.to_thread(app.session.robot_side)

    def polled(view: RobotSideView) -> None:
        before = app.sampler.robot_side
        app.sampler.robot_side_polled(view)
        if before is None or before.enabled != view.enabled:
            with contextlib.suppress(Exception):  # the app may be leaving: no screen to refresh
                app.refresh_frame(force=True)  # the footer reads the frame
                app.screen.refresh_bindings()

    app.run_worker(poll_forever(ask, PERIOD_S, polled), group="robot-side", exclusive=True)


def go(app: ArbiterApp) -> None:
    """``g`` in observe mode: start the robot-side controller (a worker's thread)."""
    start = partial(_start, app)
    app.run_worker(start, thread=True, group="robot-side-go", exclusive=True, exit_on_error=False)


def _start(app: ArbiterApp) -> None:
    try:
        said = app.session.start_robot_side()
    except AutonomyUnavailable as exc:
        app.call_from_thread(app.notify, f"robot-side controller: {exc}", severity="error", markup=False)
        return
    app.sampler.robot_side_polled(app.session.robot_side())
    app.call_from_thread(app.notify, said, timeout=4, markup=False)
    app.call_from_thread(app.refresh_frame, True)
