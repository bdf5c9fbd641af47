"""The Textual app: it composes the console and does nothing else.

The robot session (``session/robot.py``) drives and records; the frame sampler (``session/frames.py``)
turns it into one frozen frame at the UI rate; the pollers (``session/pollers.py``) bring the tracker's
answers; the key router (``keys.py``) takes teleop keys on the input thread; the palette's commands are in
``palette.py``. Screens call the session and ask for a fresh frame (:class:`~.screens.base.Console`);
each widget picks its part of the frame. Events are past-tense messages (``messages.py``). The first
frame is painted at once: the link (and the embedded backend) start in a worker while the status line
says ``STARTING``.
"""

from __future__ import annotations

import contextlib
import logging
import signal
import time
from collections.abc import Callable, Iterable
from functools import partial
from typing import Any

from textual import events, on
from textual.app import App, SystemCommand
from textual.binding import Binding, BindingType
from textual.command import CommandPalette
from textual.driver import Driver
from textual.screen import Screen
from textual.widgets import Input, TextArea

from ..analytics.store import AnalyticsStore
from ..latency.tracker_client import TrackerClient
from ..link.base import Link, PendingLink
from ..session.config import save_theme
from ..session.frames import CONTROL, Frame, FrameClock, FrameSampler, Shown
from ..session.robot import RobotSession
from ..session.settings import Settings
from ..terminal import fewer_bytes
from . import lifecycle, operator, palette, perf, robot_side, sweep
from .dialogs import Dialogs
from .keys import STOP_BINDINGS, TYPING, KeyRouter, direct_keys
from .messages import (
    BackendFailed,
    BackendStarted,
    FrameDue,
    GoalPicked,
    RecordingOpened,
    Said,
    session_said,
)
from .perf import give_way
from .perf.heap import freeze_heap
from .perf.theme import RegistryTheme
from .screens.analytics import AnalyticsScreen
from .screens.base import BaseScreen
from .screens.control import ControlScreen
from .screens.help import HelpScreen
from .screens.latency import LatencyScreen
from .screens.topics import TopicsScreen

log = logging.getLogger(__name__)
EXIT_DEADLINE_S = 2.0  # after SIGHUP/SIGTERM the process is gone by then, whatever the terminal does


SCREENS: dict[str, str | Callable[[], Screen[Any]]] = {
    "control": ControlScreen,
    "analytics": AnalyticsScreen,
    "latency": LatencyScreen,
    "topics": TopicsScreen,
}
KEYS: list[BindingType] = [
    Binding("ctrl+c", "stop_and_quit", "Quit", priority=True, show=False),
    Binding("ctrl+q", "stop_and_quit", "Quit", priority=True),
    # short labels: the footer fits in 80 columns on every screen (full names in ? help and ctrl+p)
    Binding("1", "mode('control')", "Drive", tooltip="The control screen"),
    Binding("2", "mode('analytics')", "Stats", tooltip="The analytics screen"),
    Binding("3", "mode('latency')", "Link", tooltip="The latency screen: the link's latency"),
    Binding("4", "mode('topics')", "Topics", tooltip="The topics screen: is every topic alive?"),
    *STOP_BINDINGS,
    Binding("question_mark", "help", "Help"),
]


class ArbiterApp(RegistryTheme):
    """The console: four screens over one robot session (one link, one analytics store, one control
    loop) and one tracker, injected (:func:`make_app`) or the link made by a ``connector`` after the first
    frame. Every way out stops the robot first; the stop keys stop whatever drives, anywhere."""

    TITLE = "arbiter-tui"
    MODES = SCREENS
    DEFAULT_MODE = "control"
    BINDINGS = KEYS

    def __init__(
        self,
        settings: Settings,
        link: Link,
        tracker: TrackerClient | None = None,
        store: AnalyticsStore | None = None,
        clock: Callable[[], float] = time.monotonic,
        connector: lifecycle.Connector | None = None,
    ) -> None:
        super().__init__()
        self.settings = settings
        self.tracker = tracker
        self._connector = connector
        self._cleanup: Callable[[], None] | None = None
        self.session = RobotSession(settings, link, store, clock)
        self.session.on_event = self._session_event  # from the session's thread: post_message is safe
        self.session.autonomy = None if tracker is None else tracker.autonomy()
        self.sampler = FrameSampler(self.session, settings, tracker=tracker)
        self.frame_clock: FrameClock | None = None  # live only: frames after control ticks
        self.keys = KeyRouter(self.session.key, lambda: self.session.stop_all("stop key"), self.session.clock)
        self.dialogs = Dialogs(self, self)
        self._shown_state: tuple[object, ...] = ()
        self._theme_loaded = False

    @property
    def frame(self) -> Frame:  # the frame on screen now
        return self.sampler.frame

    def _session_event(self, event: object) -> None:
        if (said := session_said(event)) is not None:
            self.post_message(said)

    # -- lifecycle -------------------------------------------------------------------------------------
    def on_mount(self) -> None:
        if self.settings.theme:
            self.theme = self.settings.theme
        self._theme_loaded = True
        for note in self.settings.notes:
            self.notify(note, severity="warning", timeout=8)
        self.refresh_frame(force=True)
        self.call_after_refresh(freeze_heap)  # what start made, once it is on screen
        if self.settings.live:
            # the robot's clock (control, sampling, simulation, on their own thread) says when to paint
            self.frame_clock = lifecycle.frames_after_ticks(self, self.sampler)
            self.session.start()
            operator.watch(self)  # does the person's terminal still hear the console?
            if self._connector is not None:  # the link (and the backend) start after the first frame
                connect = partial(lifecycle.connect, self._connector, self)
                self.run_worker(connect, thread=True, group="connect", exclusive=True, exit_on_error=False)
            else:
                self._poll()
        if self.settings.handle_signals:
            lifecycle.on_hangup(self._on_signal)

    def watch_theme(self, theme: str) -> None:
        """A theme chosen in the palette is kept in the config file for next time."""
        if not self._theme_loaded or self.settings.config_path is None or theme == self.settings.theme:
            return
        self.settings.theme = theme
        try:
            save_theme(self.settings.config_path, theme)
        except OSError as exc:
            self.notify(f"could not save the theme in {self.settings.config_path}: {exc}", severity="warning")

    @on(BackendStarted)
    def _backend_started(self, event: BackendStarted) -> None:
        self.session.attach(event.link)
        self.session.autonomy = None if event.tracker is None else event.tracker.autonomy()
        self.tracker = self.sampler.tracker = event.tracker
        self._cleanup = event.cleanup
        self._poll()
        self.refresh_frame(force=True)

    @on(BackendFailed)
    def _start_failed(self, event: BackendFailed) -> None:
        self.sampler.start_error = event.error
        self.notify(f"could not start: {event.error}", severity="error", timeout=30)
        self.refresh_frame(force=True)

    def _poll(self) -> None:
        """The tracker's pollers (``lifecycle.poll``), and observe mode's robot-side controller."""
        if self.tracker is not None and self.settings.live:
            lifecycle.poll(self, self.tracker, self.sampler, lambda: _shown(self))
            if self.settings.observe:  # g starts it there, and the panel says how it is
                robot_side.poll(self)

    def _on_signal(self, sig: int) -> None:
        lifecycle.exit_within(EXIT_DEADLINE_S)  # first: finishing the journal may wait on a stalled disk
        self.session.hang_up(f"signal {signal.Signals(sig).name}")
        self.exit()

    async def on_unmount(self) -> None:
        self.session.close()  # one zero, and the clocked work ends
        give_way.install(None)
        if self.tracker is not None:
            with contextlib.suppress(Exception):
                await self.tracker.aclose()

    def close_link(self) -> None:
        """After the app has exited: close the link and stop what the connector started."""
        with contextlib.suppress(Exception):
            self.session.link.close()
        if self._cleanup is not None:
            self._cleanup()

    def on_app_blur(self, event: events.AppBlur) -> None:
        self.session.stop("terminal lost focus")

    # -- frames ------------------------------------------------------------------------------------------
    @on(FrameDue)
    def _frame_due(self, event: FrameDue) -> None:
        self.sample_frame()
        event.clock.drawn()

    def refresh_frame(self, force: bool = False) -> None:
        """After a user action: a new frame now if what the user waits to see changed (a new command or
        limit shows at once; a held key's repeats that change nothing wait for the UI tick), or
        ``force`` (past every rate gate: a selection, a screen shown)."""
        if force or self.sampler.user_state() != self._shown_state:
            self.sample_frame(force, echo=not force)

    def sample_frame(self, force: bool = False, echo: bool = False) -> None:
        """A new frame for the screens shown (the UI tick: ``ui_rate`` frames a second, each just after a
        control tick); ``echo``: what a key changed alone (``FrameSampler.sample``)."""
        stack = _screens(self)
        if not stack:
            return
        state = self.sampler.user_state()
        self._shown_state = state
        shown = _shown(self)
        frame = self.sampler.sample(shown, force, echo)
        for screen in stack:
            if isinstance(screen, BaseScreen) and (frame is not screen.frame or screen.plot_budget.waiting):
                # a tick's frame draws at most one plot, a key's echo none
                screen.plot_budget.renew(None if force else 0 if echo else 1)
                screen.frame = frame  # (the same frame again: only for the plots that waited)
        if shown.shows("analytics"):
            sweep.start_if_wanted(self, self.session, self.sampler)

    # -- keys --------------------------------------------------------------------------------------------
    def get_driver_class(self) -> type[Driver]:
        return fewer_bytes(direct_keys(super().get_driver_class(), lambda: self.keys))

    async def on_event(self, event: events.Event) -> None:
        if isinstance(event, events.Key) and not event.is_forwarded:
            if self.keys.taken(event):  # answered on the input thread: show it; nobody answers it again
                self.app_focus = True
                self.refresh_frame()
                return
            try:
                await super().on_event(event)
            finally:
                # The screen answers it from its own queue; a key its handler does not use bubbles back to
                # the app's queue, where the bindings answer it. So: handled once the screen's queue,
                # then the app's, reach this point.
                self.screen.call_later(
                    self.call_later, lambda: self.keys.handled(isinstance(self.screen, ControlScreen))
                )
            return
        await super().on_event(event)

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """space and k stop but in a text input, where ctrl+k stops and the footer names it (``TYPING``)."""
        if action != "stop" or not parameters:
            return True
        return isinstance(self.focused, (Input, TextArea)) == (parameters == (TYPING,))

    def action_command_palette(self) -> None:
        """The palette, saying in its prompt and its footer how to stop the robot while typing in it."""
        if self.use_command_palette and not CommandPalette.is_open(
            self  # type: ignore[arg-type]  # Textual wants an App[object], and App[T] is invariant
        ):
            self.push_screen(palette.StopPalette())

    def get_system_commands(self, screen: Screen[object]) -> Iterable[SystemCommand]:
        yield from super().get_system_commands(screen)
        shown = self.sampler.recording is not None
        yield from palette.commands(self, self, self.action_mode, recording_shown=shown)

    # -- what needs the app: notices and dialogs -------------------------------------------------------
    def go(self, restart: bool = False) -> bool:
        """``g``: resume an interrupted mission or start the selected one; ``restart``: from waypoint 1.
        In observe mode the console drives no mission: ``g`` starts the robot-side controller."""
        if self.settings.observe:
            robot_side.go(self)
            return True
        why = self.session.go(restart)
        if why is not None and not self.session.too_small:
            self.notify(why, severity="warning")
        elif (notice := self.session.take_notice()) is not None:
            self.notify(notice, timeout=6)
        self.refresh_frame(force=True)
        return why is None

    @on(GoalPicked)
    def _goal_picked(self, event: GoalPicked) -> None:
        """Drive to the goal with go_to_goal (or the autonomous controller already selected)."""
        if self.session.too_small:
            return
        if self.settings.observe:
            self.notify(robot_side.NO_GOALS, severity="warning")
            return
        try:
            self.session.go_to(event.x, event.y)
        except ValueError as exc:
            self.notify(str(exc), severity="error")
            return
        self.notify(f"{self.session.loop.algorithm} driving to ({event.x:+.2f}, {event.y:+.2f})", timeout=3)
        self.refresh_frame(force=True)

    @on(Said)
    def _said(self, event: Said) -> None:
        """Every event the user is told about (``messages.Said``); a recording also replaces the live
        analytics (or gives them back)."""
        if isinstance(event, RecordingOpened):
            self.sampler.recording_opened(event.view)
            self.refresh_frame(force=True)
        n = event.notice()
        if n is not None:
            say = partial(self.notify, n.text, severity=n.severity, timeout=n.timeout, markup=False)
            self.set_timer(n.after_s, say) if n.after_s else say()

    # -- actions -------------------------------------------------------------------------------------------
    def action_mode(self, name: str) -> None:
        if name != self.current_mode:
            self.switch_mode(name)

    def action_help(self) -> None:
        if not isinstance(self.screen, HelpScreen):
            self.push_screen(HelpScreen())

    def action_stop(self, where: str = "") -> None:
        """Every stop key (space, k, ctrl+k), on every screen and dialog: ``RobotSession.stop_all``
        (``where``: the keys' condition, ``check_action``'s)."""
        self.session.stop_all("stop key")
        self.refresh_frame()

    async def action_stop_and_quit(self) -> None:
        self.session.stop("quit")
        self.exit()


def _screens(app: App[None]) -> list[Screen[object]]:
    """The screens shown; none while the app exits (the mode's stack emptied, or already gone)."""
    try:
        return app.screen_stack
    except KeyError:
        return []


def _shown(app: App[None]) -> Shown:
    """What is on screen (a poller may still ask while the app exits: then nothing)."""
    stack = _screens(app)
    top = stack[-1] if stack else None
    dashboard = app.current_mode == CONTROL and isinstance(top, ControlScreen) and top.dashboard
    return Shown(app.current_mode, dashboard)


def make_app(
    settings: Settings,
    link: Link | None = None,
    tracker: TrackerClient | None = None,
    store: AnalyticsStore | None = None,
    clock: Callable[[], float] = time.monotonic,
    connector: lifecycle.Connector | None = None,
) -> ArbiterApp:
    """Build the app for the CLI and for tests alike: with a link injected, or a ``connector`` that
    makes one in a worker once the first frame is on screen. The Textual patches (``perf``) are
    installed here, at start-up, where this install's releases were checked for them."""
    perf.install()
    return ArbiterApp(
        settings, link or PendingLink(), tracker=tracker, store=store, clock=clock, connector=connector
    )
