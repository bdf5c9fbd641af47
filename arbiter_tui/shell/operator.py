"""The shell's part of the heartbeat (``session/heartbeat.py``): the queries written behind the frames,
or tmux asked about its clients, and the answers handed to the session's ``OperatorWatch``.

The query goes through Textual's writer like a frame (never interleaved with one) from a UI timer: a UI
thread blocked on a full terminal sends no query, gets no answer, and the session (on its own thread)
holds the mission. The answers come on the driver's input thread (``keys.direct_keys``).
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import threading
import time
from typing import TYPE_CHECKING

from ..session.heartbeat import (
    PERIOD_S,
    QUERY,
    TMUX,
    TMUX_PERIOD_S,
    Heartbeat,
    multiplexer,
    tmux_attached,
    unknown_words,
)

if TYPE_CHECKING:
    from .app import ArbiterApp


def watch(app: ArbiterApp) -> None:
    """Arm the session's operator watch for the terminal the console runs in (a live console in a real
    terminal with ``--operator-timeout`` above 0)."""
    watch_ = app.session.operator
    if watch_.timeout_s <= 0 or not app.settings.live or app.is_headless:
        return
    app.keys.reported = watch_.heard  # the answers, from the driver's input thread
    mux = multiplexer(os.environ)
    if mux == TMUX:  # tmux answers the queries itself: ask it whether a client is attached instead
        heartbeat = Heartbeat(watch_.timeout_s + TMUX_PERIOD_S, TMUX)
        watch_.arm(heartbeat)
        _poll_tmux(app, heartbeat)
        return
    if mux is not None:
        watch_.arm(None, unknown_words(mux))
        return
    heartbeat = Heartbeat(watch_.timeout_s)
    watch_.arm(heartbeat)

    def ask() -> None:
        driver = app._driver  # Textual's writer: the query queued behind the frames written before it
        if driver is None:
            return
        now = time.monotonic()
        clock, lag = app.frame_clock, heartbeat.lag_s(now)
        if clock is not None and lag is not None:  # a link slower than the screen: fewer frames
            clock.echoed(lag)
            app.sampler.slow_stretch = clock.stretch
        heartbeat.asked(now)
        driver.write(QUERY)

    app.set_interval(PERIOD_S, ask)


def tmux_command(pane: str | None) -> list[str]:
    """``tmux display``'s question: how many clients are attached to this pane's session."""
    return ["tmux", "display-message", "-p", *(["-t", pane] if pane else []), "#{session_attached}"]


def _poll_tmux(app: ArbiterApp, heartbeat: Heartbeat) -> None:
    """Once a second on a thread of its own (a process each time): a client attached is an answer."""
    command = tmux_command(os.environ.get("TMUX_PANE"))

    def poll() -> None:
        while app.is_running:
            heartbeat.asked(time.monotonic())
            out = ""
            with contextlib.suppress(OSError, subprocess.SubprocessError):
                out = subprocess.run(command, capture_output=True, text=True, timeout=2.0).stdout
            if tmux_attached(out):
                heartbeat.heard(time.monotonic())
            time.sleep(TMUX_PERIOD_S)

    threading.Thread(target=poll, name="operator-tmux", daemon=True).start()
