"""The analytics screen's error-vs-latency sweep (``session/link_sweep.py``: ``arbiter-tui compare`` in a
niced child process, cached on disk), started as a worker when the screen shows it and the sampler says
the selected mission's curve is wanted; its curve, or why it failed, goes back to the sampler. Whatever
fails, the sweep ends ``FAILED`` and says why: never left running, and tried again later
(``FrameSampler.sweep_wanted``)."""

from __future__ import annotations

import logging
from dataclasses import replace
from typing import Any

from textual.app import App

from ..analytics.linkcurve import FAILED, READY, CurveError
from ..session.frames import FrameSampler
from ..session.link_sweep import sweep_curve
from ..session.robot import RobotSession
from .messages import LinkSweepFailed, unexpected

log = logging.getLogger(__name__)


def start_if_wanted(app: App[Any], session: RobotSession, sampler: FrameSampler) -> None:
    mission = sampler.sweep_wanted()
    if mission is not None:
        sweep = _sweep(app, session, sampler, mission)
        app.run_worker(sweep, exclusive=True, group="link-sweep", exit_on_error=False)


async def _sweep(app: App[Any], session: RobotSession, sampler: FrameSampler, mission: str) -> None:
    teleop = session.teleop
    try:
        curve = await sweep_curve(mission, teleop.speed, teleop.turn, pause=sampler.sweep_pause)
    except Exception as exc:  # (a cancellation is not: the sweep that replaces it is running)
        if isinstance(exc, (CurveError, OSError)):
            why = str(exc) or type(exc).__name__
        else:  # a fault of ours: said as well, and logged with its traceback
            log.exception("the latency sweep failed")
            why = unexpected(exc)
        sampler.sweep_changed(replace(sampler.frame.link_sweep, state=FAILED, error=why))
        app.post_message(LinkSweepFailed(why))
        return
    sampler.sweep_changed(replace(sampler.frame.link_sweep, state=READY, curve=curve))
