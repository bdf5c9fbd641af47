"""The Textual app: three modes (control, analytics, latency) over one store, one link, one poller.

Data reaches the screens as frozen snapshots in the app's reactive attributes (``views.py``), sampled
at the UI rate from sources written on other threads; events are past-tense messages
(``messages.py``). The first frame is painted at once: the link (and the embedded backend) start in a
worker while the status line says ``STARTING``.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import replace
from pathlib import Path

from textual import events, on, work
from textual.app import App, SystemCommand
from textual.binding import Binding
from textual.driver import Driver
from textual.message import Message
from textual.reactive import var
from textual.screen import Screen

from ..analytics.files import FORMATS
from ..analytics.linkcurve import FAILED, READY, RUNNING, CurveError, LinkSweepView, measured_p95
from ..analytics.store import AnalyticsStore
from ..control.algorithms import ALGORITHMS, MISSIONS
from ..control.loop import ControlLoop
from ..control.teleop import TELEOP_KEYS, Teleop, key_name
from ..latency.topics_client import PERIOD_S as TOPICS_PERIOD_S
from ..latency.topics_client import TopicsPoller, TopicsState
from ..latency.topics_table import echo_refusal, echo_text
from ..latency.tracker_client import LatencyView, TrackerClient
from ..link.base import STARTING, Link, PendingLink
from ..session.config import save_theme
from ..session.link_sweep import sweep_curve
from ..session.robot import MissionFinished, RobotSession
from ..session.settings import SIM, Settings
from ..session.views import (
    AnalyticsView,
    LatencySnapshot,
    MapView,
    RobotView,
    StatusView,
    analytics_view,
    latency_snapshot,
    map_view,
    robot_view,
    status_view,
)
from .messages import (
    BackendFailed,
    BackendStarted,
    DataCleared,
    ExportFailed,
    ExportResult,
    ExportWritten,
    GoalPicked,
    LatencyPolled,
    LinkStateChanged,
    LinkSweepFailed,
    RunFinished,
)
from .screens.analytics import AnalyticsScreen
from .screens.control import ControlScreen
from .screens.help import HelpScreen
from .screens.latency import LatencyScreen
from .screens.topics import TopicsScreen

log = logging.getLogger(__name__)
FREEZE_AFTER_S = 2.0
NOTICE_AFTER_STOP_S = 0.1  # a run's end is told once its stop command has reached the robot
COUNT_PERIOD_S = 1.0  # the status line's sample count follows at most this often


def freeze_heap() -> None:
    """Move every object alive now into the garbage collector's permanent generation.

    A full (generation 2) collection walks every tracked object while holding the GIL; the console's
    heap (Textual's widgets, styles, caches) made that 100-500 ms on a Pi-class CPU (bench/pi.py, gc
    callbacks), during which the session thread could not send a command. The widgets and caches made
    at start and on each screen's first showing live as long as the console, so they need never be walked
    again: a full collection then only walks what was made since. Cheap (a list splice) and called a
    handful of times, so the garbage frozen with them stays a one-off."""
    gc.freeze()


EXIT_DEADLINE_S = 2.0  # after SIGHUP/SIGTERM the process is gone by then, whatever the terminal does


def direct_keys(base: type[Driver]) -> type[Driver]:
    """``base`` (the terminal driver Textual chose) with teleop keys offered to the app on the driver's
    input thread, before they join the UI's queue (``ArbiterApp.key_on_input_thread``)."""

    class DirectKeysDriver(base):  # type: ignore[misc, valid-type]
        def process_message(self, message: Message) -> None:
            if isinstance(message, events.Key) and isinstance(self._app, ArbiterApp):
                self._app.key_on_input_thread(message)
            super().process_message(message)

    DirectKeysDriver.__name__ = f"DirectKeys{base.__name__}"
    return DirectKeysDriver


Connector = Callable[[], tuple[Link, "TrackerClient | None", Callable[[], None]]]


class ArbiterApp(App[None]):
    """The console: three modes (control, analytics, latency) over one link, one analytics store (the
    seed's singleton), one control loop and one tracker poller. The link, poller, store and clock are
    injected (:func:`make_app`), or the link is made by a ``connector`` in a worker after the first
    frame. Every way out (quit, signal, focus loss, a terminal too small) stops the robot first; an
    autonomous run keeps driving while another screen is shown, and space or k stop it anywhere."""

    TITLE = "arbiter-tui"
    MODES = {
        "control": ControlScreen,
        "analytics": AnalyticsScreen,
        "latency": LatencyScreen,
        "topics": TopicsScreen,
    }
    DEFAULT_MODE = "control"
    BINDINGS = [
        Binding("ctrl+c", "stop_and_quit", "Quit", priority=True, show=False),
        Binding("ctrl+q", "stop_and_quit", "Quit", priority=True),
        # short labels: the footer fits in 80 columns on every screen (full names in ? help and ctrl+p)
        Binding("1", "mode('control')", "Drive", tooltip="The control screen"),
        Binding("2", "mode('analytics')", "Stats", tooltip="The analytics screen"),
        Binding("3", "mode('latency')", "Link", tooltip="The latency screen: the link's latency"),
        Binding("4", "mode('topics')", "Topics", tooltip="The topics screen: is every topic alive?"),
        Binding("space", "stop", "Stop"),
        Binding("k", "stop", "Stop", show=False),
        Binding("question_mark", "help", "Help"),
    ]

    # What the widgets show: replaced (never mutated) at the UI rate; equal values notify nobody.
    status: var[StatusView] = var(StatusView)
    robot: var[RobotView] = var(RobotView)
    trajectory: var[MapView] = var(MapView)
    analytics: var[AnalyticsView] = var(AnalyticsView)
    latency: var[LatencySnapshot] = var(LatencySnapshot)
    topics: var[TopicsState] = var(TopicsState)
    link_sweep: var[LinkSweepView] = var(LinkSweepView)  # error vs latency, and the measured p95 on it
    ui_tick: var[int] = var(0)  # one more at the end of every sampling: one frame for all that changed

    def __init__(
        self,
        settings: Settings,
        link: Link,
        tracker: TrackerClient | None = None,
        store: AnalyticsStore | None = None,
        clock: Callable[[], float] = time.monotonic,
        connector: Connector | None = None,
    ) -> None:
        super().__init__()
        self.settings = settings
        self.tracker = tracker
        self._connector = connector
        self._cleanup: Callable[[], None] | None = None
        self.session = RobotSession(settings, link, store, clock)
        self.session.on_event = self._session_event  # from the session's thread: post_message is safe
        self.last_export: ExportResult | None = None
        self.start_error: str | None = None
        self._link_state: str | None = None
        self._shown_command: tuple[object, ...] = ()
        self._analytics_at = float("-inf")
        self._sweep_version = -1  # the store version the measured p95 is from
        self._latency_at = float("-inf")
        self._echo: tuple[str, str] | None = None  # the topics screen's echo (written on the link's thread)
        self._echo_cancel: Callable[[], None] | None = None
        self._echo_lock = threading.Lock()  # a late message of the last topic must not overwrite this one's
        self._count_at = float("-inf")  # when the status line's sample count last changed
        self._frozen_modes: set[str] = set()
        # Teleop keys straight from the input thread (see key_on_input_thread)
        self._keys_lock = threading.Lock()
        self._keys_direct = False  # the control screen is in front, no dialog over it, no key queued
        self._keys_queued = 0  # keys passed to the UI that it has not answered yet
        self._keys_taken: set[int] = set()  # ids of key events the session already answered

    # The session's parts, for the screens and the views (the session owns them).
    @property
    def link(self) -> Link:
        return self.session.link

    @property
    def loop(self) -> ControlLoop:
        return self.session.loop

    @property
    def teleop(self) -> Teleop:
        return self.session.teleop

    @property
    def store(self) -> AnalyticsStore:
        return self.session.store

    @property
    def clock(self) -> Callable[[], float]:
        return self.session.clock

    @clock.setter
    def clock(self, clock: Callable[[], float]) -> None:
        self.session.clock = clock

    @property
    def too_small(self) -> bool:
        return self.session.too_small

    @property
    def stop_reason(self) -> str | None:
        return self.session.stop_reason

    def _session_event(self, event: object) -> None:
        if isinstance(event, MissionFinished):
            self.post_message(RunFinished(event.algorithm, event.mission))

    # -- lifecycle -------------------------------------------------------------------------
    def on_mount(self) -> None:
        if self.settings.theme:
            self.theme = self.settings.theme
        self._theme_loaded = True
        for note in self.settings.notes:
            self.notify(note, severity="warning", timeout=8)
        self.publish_views(force=True)
        self.set_timer(FREEZE_AFTER_S, freeze_heap)
        if self.settings.live:
            self.session.start()  # the robot's clock: control, sampling, simulation on their own thread
            self.set_interval(1.0 / self.settings.ui_rate, self.publish_views)
            if self._connector is not None:
                self._connect()
            elif self.tracker is not None:
                self._poll_forever()
                self._poll_topics_forever()
        if self.settings.handle_signals:
            loop = asyncio.get_running_loop()
            for sig in (signal.SIGHUP, signal.SIGTERM):
                with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
                    loop.add_signal_handler(sig, self._on_signal, sig)

    _theme_loaded = False

    def watch_theme(self, theme: str) -> None:
        """A theme chosen in the palette is kept in the config file for next time."""
        if not self._theme_loaded or self.settings.config_path is None or theme == self.settings.theme:
            return
        self.settings.theme = theme
        try:
            save_theme(self.settings.config_path, theme)
        except OSError as exc:
            self.notify(f"could not save the theme in {self.settings.config_path}: {exc}", severity="warning")

    @work(thread=True, exclusive=True, group="connect", exit_on_error=False)
    def _connect(self) -> None:
        """Start the embedded backend (when there is one) and the link, after the first frame."""
        assert self._connector is not None
        try:
            link, tracker, cleanup = self._connector()
        except Exception as exc:  # a one-line reason on screen, never a traceback
            log.exception("starting the link failed")
            self.post_message(BackendFailed(str(exc) or type(exc).__name__))
            return
        if not self.is_running:  # the user quit while it was starting
            link.close()
            cleanup()
            return
        self.post_message(BackendStarted(link, tracker, cleanup))

    def screen_shown(self, name: str | None = None) -> None:
        """A screen (or the dashboard's panes, ``name``) came to the front for the first time or again."""
        name = name or self.current_mode
        if name not in self._frozen_modes:  # its widgets, made once, kept for good
            self._frozen_modes.add(name)
            self.set_timer(FREEZE_AFTER_S, freeze_heap)

    @on(BackendStarted)
    def _attach(self, event: BackendStarted) -> None:
        self.session.attach(event.link)
        self.tracker = event.tracker
        self._cleanup = event.cleanup
        if self.tracker is not None and self.settings.live:
            self._poll_forever()
            self._poll_topics_forever()
        self.publish_views()

    @on(BackendFailed)
    def _start_failed(self, event: BackendFailed) -> None:
        self.start_error = event.error
        self.notify(f"could not start: {event.error}", severity="error", timeout=30)
        self.publish_views()

    def _on_signal(self, sig: int) -> None:
        self.stop_robot(f"signal {signal.Signals(sig).name}")
        # After a hang-up the terminal may be gone: Textual's writer thread then dies on EIO and its
        # shutdown can block forever on a full queue. The zero is already on its way (the link writes
        # it on its own thread); if the orderly exit has not finished in time, leave without it.
        watchdog = threading.Timer(EXIT_DEADLINE_S, os._exit, args=(0,))
        watchdog.daemon = True
        watchdog.start()
        self.exit()

    @work(exclusive=True, group="poll")
    async def _poll_forever(self) -> None:
        tracker = self.tracker
        assert tracker is not None
        period = self.settings.poll_period
        while True:
            started = time.monotonic()
            await tracker.poll()
            self.post_message(LatencyPolled())
            await asyncio.sleep(max(0.0, period - (time.monotonic() - started)))

    @work(exclusive=True, group="topics")
    async def _poll_topics_forever(self) -> None:
        """``GET /api/topics`` at most every ``topics_client.PERIOD_S``, only while screen 4 (or the
        dashboard, which shows its table) is shown."""
        tracker = self.tracker
        assert tracker is not None
        poller = TopicsPoller(tracker)
        while True:
            started = time.monotonic()
            if self.current_mode == "topics" or self.dashboard_shown():
                self.topics = replace(await poller.poll(), echo=self._echo)
            await asyncio.sleep(max(0.0, TOPICS_PERIOD_S - (time.monotonic() - started)))

    def echo_topic(self, name: str | None) -> None:
        """Echo ``name``'s latest message on the topics screen (None: stop), through the link's own
        throttled subscription; only one topic at a time, and only where the link can."""
        if self._echo_cancel is not None:
            with contextlib.suppress(Exception):
                self._echo_cancel()
            self._echo_cancel = None
        with self._echo_lock:
            self._echo = None
        figures = next((t for t in self.topics.topics if t.name == name), None)
        if name is None or figures is None:
            return
        echo = getattr(self.link, "echo", None)
        refusal = echo_refusal(figures) or (None if echo is not None else "not echoed: no rosbridge link")
        if refusal is not None:
            self._echo = (name, refusal)
            return
        shown = (name, "waiting for a message ...")
        with self._echo_lock:
            self._echo = shown

        def received(msg: dict[str, object]) -> None:  # the link's thread: a tuple swap, nothing else
            nonlocal shown
            text = echo_text(msg)
            with self._echo_lock:  # still this echo's (a message may come after it was removed)
                if self._echo is shown:
                    self._echo = shown = (name, text)

        self._echo_cancel = echo(name, figures.type, received)

    @on(LatencyPolled)
    def _polled(self) -> None:
        if self.settings.live:
            return  # the next UI tick shows it, in the same frame as everything else that changed
        if self.current_mode == "latency" or self.dashboard_shown():  # elsewhere nobody shows it
            self.latency = self._latency_snapshot()
        self._publish_status()

    async def on_unmount(self) -> None:
        self.session.close()  # one zero, and the clocked work ends
        if self.tracker is not None:
            with contextlib.suppress(Exception):
                await self.tracker.aclose()

    def close_link(self) -> None:
        """After the app has exited: close the link and stop what the connector started."""
        with contextlib.suppress(Exception):
            self.link.close()
        if self._cleanup is not None:
            self._cleanup()

    # -- views -----------------------------------------------------------------------------------
    def publish_views(self, force: bool = False) -> None:
        """Sample every source into snapshots; only what the current screen shows is computed, and
        the analytics at their own, lower rate unless ``force`` (a user action, a screen shown)."""
        if not self._has_screen():
            return  # the app is closing (its screens gone) while this interval's tick was due
        self._shown_command = (self.loop.command, self.teleop.speed, self.teleop.turn)
        state = self.link.state
        if self._link_state is not None and state != self._link_state:
            self.post_message(LinkStateChanged(self._link_state, state))
        self._link_state = state
        self._publish_status(force)
        mode = self.current_mode
        dashboard = self.dashboard_shown()
        if mode == "control":
            self.robot = robot_view(self.link, self.loop, self.too_small)
            self.trajectory = map_view(self.link, self.loop, self.trajectory)
        now = time.monotonic()
        rate = self.settings.analytics_rate
        if (mode == "analytics" or dashboard) and (force or now - self._analytics_at >= 1.0 / rate):
            self._analytics_at = now
            self.analytics = analytics_view(self.store, self.analytics, self.loop)
            self._follow_link_sweep()
        if (mode == "latency" or dashboard) and (force or now - self._latency_at >= 1.0 / rate):
            # at the analytics rate too: the console's own figures change with every round trip, and a
            # line repainted at the UI rate made every frame span the screen below it (bench/pi.py)
            self._latency_at = now
            self.latency = self._latency_snapshot()
        self.ui_tick += 1  # what waited for its period (plots) is drawn now, in this same frame

    def _follow_link_sweep(self) -> None:
        """The analytics screen's error-vs-latency line: the p95 of the latencies recorded (when the store
        changed), and a sweep for the selected mission when it has none yet (only while live)."""
        view = self.link_sweep
        if self._sweep_version != self.store.version:
            self._sweep_version = self.store.version
            p95 = measured_p95(self.store.column("latencyMs"))
            if p95 != view.p95_ms:
                view = self.link_sweep = replace(view, p95_ms=p95)
        mission = self.loop.mission_name
        if self.settings.live and view.state != RUNNING and view.mission != mission:
            self.link_sweep = replace(view, state=RUNNING, mission=mission, curve=None, error="")
            self._sweep(mission)

    @work(exclusive=True, group="link-sweep", exit_on_error=False)
    async def _sweep(self, mission: str) -> None:
        try:
            curve = await sweep_curve(mission, self.teleop.speed, self.teleop.turn)
        except (CurveError, OSError) as exc:
            self.link_sweep = replace(self.link_sweep, state=FAILED, error=str(exc))
            self.post_message(LinkSweepFailed(str(exc)))
            return
        self.link_sweep = replace(self.link_sweep, state=READY, curve=curve)

    @on(LinkSweepFailed)
    def _link_sweep_failed(self, event: LinkSweepFailed) -> None:
        self.notify(f"latency sweep failed: {event.error}", severity="warning", timeout=8)

    def _publish_status(self, force: bool = False) -> None:
        """The status line; a change of the sample count alone shows at most every ``COUNT_PERIOD_S``.

        While recording, the count changes with every sample (10 a second), and a status line repainted
        that often made every repaint span the whole screen: Textual renders every widget inside the box
        around all dirty regions, and the status line is the top row (py-spy and render counts at
        200x60, bench/pi.py)."""
        status = self._status_view()
        shown = self.status
        now = time.monotonic()
        if (
            not force
            and status != shown
            and replace(status, points=shown.points) == shown
            and now - self._count_at < COUNT_PERIOD_S
        ):
            return
        if status.points != shown.points:
            self._count_at = now
        self.status = status

    def _has_screen(self) -> bool:
        try:
            return bool(self.screen_stack)
        except KeyError:  # the mode's stack is already gone
            return False

    def dashboard_shown(self) -> bool:
        """The control screen is showing as the dashboard (a large terminal): it shows every view."""
        screen = self.screen
        return self.current_mode == "control" and isinstance(screen, ControlScreen) and screen.dashboard

    def _status_view(self) -> StatusView:
        return status_view(
            self.link, self.target(), self.loop, self.store, self.latency_view(),
            self.settings.mode == SIM, self.start_error,
        )  # fmt: skip

    def _latency_snapshot(self) -> LatencySnapshot:
        return latency_snapshot(
            self.latency_view(),
            self.link,
            self.settings.offset_warn_ms,
            self.settings.mode == SIM,
            self.settings.tracker_url or "",
        )

    def target(self) -> str:
        """What the console talks to, for the status line."""
        s = self.settings
        if s.mode == SIM:
            return ""  # the link state already says SIMULATED
        if s.mode == "embedded":
            transport = " ros" if s.transport == "ros" else ""
            if self.link.state == STARTING:
                return f"embedded{transport}"
            bridge = s.rosbridge_url.rsplit(":", 1)[-1]
            api = (s.tracker_url or "").rsplit(":", 1)[-1]
            return f"embedded{transport} {bridge}/{api}"
        return f"connect {s.rosbridge_url}"

    @on(LinkStateChanged)
    def _link_changed(self, event: LinkStateChanged) -> None:
        log.info("link %s -> %s", event.old, event.new)

    @on(RunFinished)
    def _run_finished(self, event: RunFinished) -> None:
        # The toast waits until the stop command the run's end sent is through: painting it at once
        # (and the terminal drawing it) took the CPU the backend needed to take that command, which then
        # arrived 10-20x slower than the others (bench/stop_command.py --tmux).
        text = f"{event.algorithm} finished the {event.mission} mission"
        self.set_timer(NOTICE_AFTER_STOP_S, lambda: self.notify(text, timeout=4))

    # -- safety ------------------------------------------------------------------------------
    def stop_robot(self, reason: str) -> None:
        """Stop teleop and autonomy and send one zero now (best effort: never raises)."""
        self.session.stop(reason)

    def end_manual_hold(self, reason: str) -> None:
        """A held teleop key ends now (one zero); an autonomous run is left driving."""
        self.session.end_manual_hold(reason)

    def set_too_small(self, small: bool) -> None:
        """While the terminal is too small to show the console, the robot stands still."""
        self.session.set_too_small(small)
        self.publish_views()

    def on_app_blur(self, event: events.AppBlur) -> None:
        self.stop_robot("terminal lost focus")

    def teleop_key(self, key: str) -> bool:
        """A key pressed on the control screen; True if teleop used it."""
        used = self.session.key(key)
        if used and (self.loop.command, self.teleop.speed, self.teleop.turn) != self._shown_command:
            # a new command or limit shows at once; a held key's repeats wait for the UI tick
            self.publish_views()
        return used

    # -- keys that do not wait for a paint ------------------------------------------------------
    def get_driver_class(self) -> type[Driver]:
        return direct_keys(super().get_driver_class())

    def set_keys_direct(self, direct: bool) -> None:
        """The control screen came to the front (True) or went behind a screen or dialog (False)."""
        with self._keys_lock:
            self._keys_direct = direct

    def key_on_input_thread(self, event: events.Key) -> None:
        """A key on Textual's input thread, before it joins the UI's queue.

        A teleop key (movement, scale, stop) on the control screen goes to the session at once: under a
        Pi-class CPU quota a paint in progress held a key 20-45 ms (bench/pi.py, key-to-wire), and the
        robot should not wait for the screen. It still goes on to the UI, marked as answered, so the
        screen shows it and nothing answers it twice. Keys keep their order: while a key the UI must
        answer (g, a, 1, ...) is queued and not yet handled, the keys after it queue behind it."""
        key = key_name(event.character, event.key)
        with self._keys_lock:
            take = self._keys_direct and self._keys_queued == 0 and key in TELEOP_KEYS
            if not take:
                self._queue_key()
        if not take:
            return
        try:
            used = self.session.key(key)
        except Exception:  # never let a key take the input thread down: the UI gets it instead
            log.exception("a key on the input thread failed")
            used = False
        with self._keys_lock:
            if used:
                self._keys_taken.add(id(event))
            else:
                self._queue_key()

    def _queue_key(self) -> None:
        """A key goes to the UI (under ``_keys_lock``): the keys after it wait for it, and until the UI
        has answered it nothing goes direct (it may open a dialog, or leave the control screen)."""
        self._keys_queued += 1
        self._keys_direct = False

    async def on_event(self, event: events.Event) -> None:
        if isinstance(event, events.Key) and not event.is_forwarded:
            with self._keys_lock:
                taken = id(event) in self._keys_taken
                self._keys_taken.discard(id(event))
            if taken:  # answered on the input thread: show it; nobody answers it again
                self.app_focus = True
                if (self.loop.command, self.teleop.speed, self.teleop.turn) != self._shown_command:
                    self.publish_views()
                return
            try:
                await super().on_event(event)
            finally:
                # The screen answers it from its own queue; a key its handler does not use bubbles back to
                # the app's queue, where the bindings answer it. So: handled once the screen's queue,
                # then the app's, reach this point.
                self.screen.call_later(self.call_later, self._key_handled)
            return
        await super().on_event(event)

    def _key_handled(self) -> None:
        with self._keys_lock:
            self._keys_queued = max(0, self._keys_queued - 1)
            if self._keys_queued == 0 and isinstance(self.screen, ControlScreen):
                self._keys_direct = True  # still the control screen, no dialog over it

    def get_system_commands(self, screen: Screen[object]) -> Iterable[SystemCommand]:
        yield from super().get_system_commands(screen)
        for name in self.MODES:
            yield SystemCommand(
                f"Screen: {name}", f"Switch to the {name} screen", lambda n=name: self.action_mode(n)
            )
        yield SystemCommand("Stop the robot", "Zero velocity now", lambda: self.stop_robot("palette"))
        for algo in ALGORITHMS:
            yield SystemCommand(
                f"Algorithm: {algo}",
                "Select the controller (g runs it)",
                lambda a=algo: self.select_algorithm(a),
            )
        for mission in MISSIONS:
            yield SystemCommand(
                f"Mission: {mission}",
                "Select the mission (g runs it)",
                lambda m=mission: self.select_mission(m),
            )
        yield SystemCommand("Go", "Resume the interrupted mission, or start the selected one (g)", self.go)
        yield SystemCommand(
            "Restart the mission", "From its first waypoint (G)", lambda: self.go(restart=True)
        )
        yield SystemCommand("Set a goal x y…", "Type a go-to-goal target in metres (t)", self.ask_goal)
        yield SystemCommand("Start/pause collection", "Toggle analytics collection", self.toggle_collection)
        yield SystemCommand("Clear collected data", "Asks first", self.ask_clear)
        for fmt in FORMATS:
            yield SystemCommand(
                f"Export {fmt.upper()}", f"Write the collected data as {fmt}", lambda f=fmt: self.export(f)
            )

    # -- driving -------------------------------------------------------------------------------
    def select_algorithm(self, name: str) -> None:
        self.session.select_algorithm(name)
        self.publish_views(force=True)

    def select_mission(self, name: str) -> None:
        self.session.select_mission(name)
        self.publish_views(force=True)

    def cycle_mission(self) -> None:
        self.session.cycle_mission()
        self.publish_views()

    def go(self, restart: bool = False) -> bool:
        """``g``: resume an interrupted mission or start the selected one; ``restart``: from waypoint 1."""
        why = self.session.go(restart)
        if why is not None and not self.too_small:
            self.notify(why, severity="warning")
        self.publish_views(force=True)
        return why is None

    def set_goal(self, x: float, y: float) -> None:
        """Drive to (x, y) with go_to_goal (or the autonomous controller already selected)."""
        if self.too_small:
            return
        try:
            self.session.go_to(x, y)
        except ValueError as exc:
            self.notify(str(exc), severity="error")
            return
        self.notify(f"{self.loop.algorithm} driving to ({x:+.2f}, {y:+.2f})", timeout=3)
        self.publish_views(force=True)

    def ask_goal(self) -> None:
        from ..control.algorithms import goal_driver
        from .screens.goal import GoalPrompt

        pose = self.link.telemetry.snapshot()[0]

        def chosen(goal: tuple[float, float] | None) -> None:
            if goal is not None:
                self.set_goal(*goal)

        self.push_screen(GoalPrompt((pose.x, pose.y), goal_driver(self.loop.algorithm)), chosen)

    @on(GoalPicked)
    def _goal_picked(self, event: GoalPicked) -> None:
        self.set_goal(event.x, event.y)

    # -- actions -------------------------------------------------------------------------------
    def action_mode(self, name: str) -> None:
        if name != self.current_mode:
            self.switch_mode(name)

    def action_help(self) -> None:
        if not isinstance(self.screen, HelpScreen):
            self.push_screen(HelpScreen())

    def action_stop(self) -> None:
        self.stop_robot("stop key")
        self.publish_views()

    async def action_stop_and_quit(self) -> None:
        self.stop_robot("quit")
        self.exit()

    def toggle_collection(self) -> None:
        self.session.toggle_collection()
        self.publish_views(force=True)

    def ask_clear(self) -> None:
        from .screens.confirm import ConfirmClear

        n = len(self.store)

        def done(confirmed: bool | None) -> None:
            if confirmed:
                self.post_message(DataCleared(self.session.clear()))

        self.push_screen(ConfirmClear(n), done)

    @on(DataCleared)
    def _cleared(self, event: DataCleared) -> None:
        self.notify(f"cleared {event.points} samples", timeout=3)
        self.publish_views(force=True)

    def export(self, *formats: str) -> list[ExportResult]:
        """Write the collected data in each format, all under one file stem; nothing when there is none."""
        results = self.session.export(*formats)
        for result in results:
            if result.path is not None:
                self.post_message(ExportWritten(result))
            elif result.nothing:
                self.notify(result.error or "", severity="warning", timeout=6)
            else:
                self.post_message(ExportFailed(result))
        if results:
            self.last_export = results[-1]
        return results

    @on(ExportWritten)
    def _export_written(self, event: ExportWritten) -> None:
        r = event.result
        where = Path(r.path).resolve() if r.path is not None else r.path  # the whole path: no guessing where
        self.notify(f"wrote {where} ({r.points} points)", timeout=4, markup=False)  # a path is no markup

    @on(ExportFailed)
    def _export_failed(self, event: ExportFailed) -> None:
        r = event.result
        text = f"EXPORT FAILED ({r.fmt}): {r.error} — collected data kept"
        self.notify(text, severity="error", timeout=8, markup=False)

    # -- shared views ------------------------------------------------------------------------------
    def latency_view(self) -> LatencyView | None:
        if self.settings.mode == SIM or self.tracker is None:
            return None
        return self.tracker.view

    def status_text(self) -> str:
        return self._status_view().text()


def make_app(
    settings: Settings,
    link: Link | None = None,
    tracker: TrackerClient | None = None,
    store: AnalyticsStore | None = None,
    clock: Callable[[], float] = time.monotonic,
    connector: Connector | None = None,
) -> ArbiterApp:
    """Build the app for the CLI and for tests alike: with a link injected, or a ``connector`` that
    makes one in a worker once the first frame is on screen."""
    return ArbiterApp(
        settings, link or PendingLink(), tracker=tracker, store=store, clock=clock, connector=connector
    )
