"""Starting and ending the console's process: the link made in a worker after the first frame, frames
paced by the robot's clock, and a hang-up or termination signal that always ends the process."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import threading
from collections.abc import Callable
from functools import partial
from typing import Any

from textual.app import App

from ..latency.topics_client import PERIOD_S as TOPICS_PERIOD_S
from ..latency.topics_client import TopicsPoller
from ..latency.tracker_client import TrackerAnswer, TrackerClient
from ..link.base import Link
from ..session.cpu_share import SPARE_CORES, cores_available
from ..session.frames import LATENCY, TOPICS, FrameClock, FrameSampler, Shown
from ..session.pollers import poll_forever
from ..session.robot import DEFAULT_CONTROL_HZ
from .messages import BackendFailed, BackendStarted, FrameDue
from .perf import give_way

log = logging.getLogger(__name__)

Connector = Callable[[], tuple[Link, "TrackerClient | None", Callable[[], None]]]


def connect(connector: Connector, app: App[Any]) -> None:
    """A worker's thread: start the embedded backend (when there is one) and the link, then tell the app
    (``BackendStarted``), or why not (``BackendFailed``: one line on screen, never a traceback)."""
    try:
        link, tracker, cleanup = connector()
    except Exception as exc:
        log.exception("starting the link failed")
        app.post_message(BackendFailed(str(exc) or type(exc).__name__))
        return
    if not app.is_running:  # the user quit while it was starting
        link.close()
        cleanup()
        return
    app.post_message(BackendStarted(link, tracker, cleanup))


def poll(app: App[Any], tracker: TrackerClient, sampler: FrameSampler, shown: Callable[[], Shown]) -> None:
    """The tracker's two pollers, each answer handed to the sampler by value: latency records (every
    ``poll_period`` while a screen shows them, else every ``idle_poll_period``, for the status line: a
    poll costs more than a bare Textual app's frame), topics while a screen shows them."""
    s = sampler.settings
    period = lambda: s.poll_period if shown().shows(LATENCY) else s.idle_poll_period  # noqa: E731
    journal = sampler.session.journal

    def polled(answer: TrackerAnswer) -> None:
        sampler.latency_polled(answer)
        if journal is not None:  # the latency window, journaled as it comes
            journal.latency(answer.window_t, answer.window)

    app.run_worker(poll_forever(tracker.poll, period, polled), group="poll", exclusive=True)
    topics = poll_forever(
        TopicsPoller(tracker).poll, TOPICS_PERIOD_S, sampler.topics_polled, lambda: shown().shows(TOPICS)
    )
    app.run_worker(topics, group="topics", exclusive=True)


def frames_after_ticks(app: App[Any], sampler: FrameSampler) -> FrameClock:
    """Frames at ``ui_rate``, each asked for just after a control tick (``FrameClock``), fewer while
    commands leave late (the session's ``tick_late_s``): the session's thread posts ``FrameDue``
    (``post_message`` is thread-safe). The analytics sweep's child is held while the robot drives
    (the sampler's ``sweep_pause``: where the console has no core to spare)."""
    session, settings, pause = sampler.session, sampler.settings, sampler.sweep_pause
    if cores_available() < SPARE_CORES:  # paints give way to the ticks (give_way.py)
        give_way.install(partial(session.schedule.give_way, give_way.GUARD_S))
    frames = FrameClock(1.0 / settings.ui_rate, 1.0 / (settings.repeat_rate or DEFAULT_CONTROL_HZ))

    def ticked() -> None:
        pause.driving(session.schedule.driving)
        if frames.ticked(session.schedule.tick_late_s):
            app.post_message(FrameDue(frames))

    session.schedule.on_tick = ticked
    return frames


def on_hangup(handler: Callable[[int], None]) -> None:
    """``handler(signal)`` on SIGHUP and SIGTERM, on the running event loop (where it can be set)."""
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGHUP, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
            loop.add_signal_handler(sig, handler, sig)


def exit_within(seconds: float) -> None:
    """The process ends within ``seconds`` whatever happens. After a hang-up the terminal may be gone:
    Textual's writer thread then dies on EIO and its shutdown can block forever on a full queue. The
    robot's zero is already on its way (the link writes it on its own thread); if the orderly exit has
    not finished in time, leave without it."""
    watchdog = threading.Timer(seconds, os._exit, args=(0,))
    watchdog.daemon = True
    watchdog.start()
