"""Observe mode's robot-side controller, from the console: asked how it is once a second (the panel
says it, and the footer offers a, n and g only where the backend runs one), and started by ``g`` on the
selected controller and mission. The requests run on worker threads (``RobotSession.robot_side`` and
``start_robot_side`` block on the backend's API); what they answer goes to the frame sampler on the UI's
thread (the sampler is not thread-safe). Whatever fails is said: the panel says a poll that failed, a
notice a start that failed."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from functools import partial
from typing import TYPE_CHECKING

from ..latency.autonomy import AutonomyUnavailable, RobotSideView
from ..session.pollers import poll_forever
from .messages import unexpected

if TYPE_CHECKING:
    from .app import ArbiterApp

log = logging.getLogger(__name__)
PERIOD_S = 1.0
NO_GOALS = "observe mode: the console drives no goal here (g starts the robot-side controller)"


def poll(app: ArbiterApp) -> None:
    """Ask the robot-side controller how it is every ``PERIOD_S`` while the app runs."""

    async def ask() -> RobotSideView:
        try:
            return await asyncio.to_thread(app.session.robot_side)
        except Exception as exc:  # a fault of ours: the panel says it, and the poller asks again
            log.exception("asking the robot-side controller failed")
            return RobotSideView(known=True, text=f"cannot ask: {unexpected(exc)}")

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
    """A worker's thread: start it, then ask how it is; the answers go to the UI's thread."""
    try:
        said = app.session.start_robot_side()
        view = app.session.robot_side()
    except Exception as exc:
        if not isinstance(exc, AutonomyUnavailable):
            log.exception("starting the robot-side controller failed")
        why = str(exc) if isinstance(exc, AutonomyUnavailable) else unexpected(exc)
        app.call_from_thread(app.notify, f"robot-side controller: {why}", severity="error", markup=False)
        return
    app.call_from_thread(_started, app, view, said)


def _started(app: ArbiterApp, view: RobotSideView, said: str) -> None:
    """The UI's thread: the robot-side controller started; the panel shows how it is."""
    app.sampler.robot_side_polled(view)
    app.notify(said, timeout=4, markup=False)
    app.refresh_frame(True)
