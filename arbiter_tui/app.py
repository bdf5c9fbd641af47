"""The Textual app: three modes (control, analytics, latency) over one store, one link, one poller."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Iterable

from textual import events
from textual.app import App, ScreenStackError, SystemCommand
from textual.binding import Binding
from textual.screen import Screen

from .analytics.files import ExportError, export_store
from .analytics.store import STORE, AnalyticsStore
from .control.loop import ControlLoop
from .control.teleop import Teleop
from .latency.tracker_client import LatencyView, TrackerClient
from .link.base import DISCONNECTED, RECONNECTING, Link
from .link.sim import SimLink
from .screens.analytics import AnalyticsScreen
from .screens.control import ControlScreen
from .screens.help import HelpScreen
from .screens.latency import LatencyScreen
from .settings import SIM, Settings

log = logging.getLogger(__name__)
EXIT_DEADLINE_S = 2.0  # after SIGHUP/SIGTERM the process is gone by then, whatever the terminal does


class ArbiterApp(App[None]):
    TITLE = "arbiter-tui"
    MODES = {"control": ControlScreen, "analytics": AnalyticsScreen, "latency": LatencyScreen}
    DEFAULT_MODE = "control"
    BINDINGS = [
        Binding("ctrl+c", "stop_and_quit", "Quit", priority=True, show=False),
        Binding("ctrl+q", "stop_and_quit", "Quit", priority=True),
        Binding("1", "mode('control')", "Control"),
        Binding("2", "mode('analytics')", "Analytics"),
        Binding("3", "mode('latency')", "Latency"),
        Binding("question_mark", "help", "Help"),
    ]

    def __init__(
        self,
        settings: Settings,
        link: Link,
        tracker: TrackerClient | None = None,
        store: AnalyticsStore = STORE,
        clock: Callable[[], float] = time.monotonic,
        on_exit: Callable[[], None] | None = None,
    ) -> None:
        super().__init__()
        self.settings = settings
        self.link = link
        self.tracker = tracker
        self.store = store
        self.clock = clock
        self._on_exit = on_exit
        self.teleop = Teleop(speed=settings.speed, turn=settings.turn, key_timeout=settings.key_timeout)
        self.loop = ControlLoop(link, store, self.teleop)
        self.export_message: str | None = None
        self.stop_reason: str | None = None
        store.collection_rate = settings.collection_rate
        if store.max_data_points != settings.max_points:
            store.max_data_points = settings.max_points

    # -- lifecycle -------------------------------------------------------------------------
    def on_mount(self) -> None:
        if self.settings.live:
            self.set_interval(1.0 / self.settings.repeat_rate, self._control_tick)
            self.set_interval(1.0 / self.store.collection_rate, self._sample)
            self.set_interval(1.0 / self.settings.ui_rate, self._redraw)
            if isinstance(self.link, SimLink):
                self.set_interval(1.0 / 50.0, self.link.step)
            if self.tracker is not None:
                self.run_worker(self._poll_forever(), name="tracker-poll", group="poll", exclusive=True)
        if self.settings.handle_signals:
            loop = asyncio.get_running_loop()
            for sig in (signal.SIGHUP, signal.SIGTERM):
                with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
                    loop.add_signal_handler(sig, self._on_signal, sig)

    def _on_signal(self, sig: int) -> None:
        self.stop_robot(f"signal {signal.Signals(sig).name}")
        # After a hang-up the terminal may be gone: Textual's writer thread then dies on EIO and its
        # shutdown can block forever on a full queue. The zero is already on its way (the link writes
        # it on its own thread); if the orderly exit has not finished in time, leave without it.
        watchdog = threading.Timer(EXIT_DEADLINE_S, os._exit, args=(0,))
        watchdog.daemon = True
        watchdog.start()
        self.exit()

    async def _poll_forever(self) -> None:
        assert self.tracker is not None
        period = self.settings.poll_period
        while True:
            started = time.monotonic()
            await self.tracker.poll()
            await asyncio.sleep(max(0.0, period - (time.monotonic() - started)))

    def _control_tick(self) -> None:
        try:
            self.link.telemetry.meter.expire(time.monotonic())  # unreported commands become "lost"
            self.loop.tick_control(self.clock())
        except Exception:  # a failing link must not take the console (and its stop keys) down
            log.exception("control tick failed")

    def _sample(self) -> None:
        try:
            self.loop.sample()
        except Exception:
            log.exception("sampling failed")

    def _redraw(self) -> None:
        try:
            screen = self.screen
        except ScreenStackError:  # mid mode-switch the new mode's stack is briefly empty: skip this frame
            return
        refresh = getattr(screen, "refresh_view", None)
        if refresh is None:
            return
        try:
            refresh()
        except Exception:
            log.exception("redraw failed")

    async def on_unmount(self) -> None:
        self.stop_robot("quit")
        if self.tracker is not None:
            with contextlib.suppress(Exception):
                await self.tracker.aclose()

    # -- safety ------------------------------------------------------------------------------
    def stop_robot(self, reason: str) -> None:
        """Stop teleop and autonomy and send one zero now (best effort: never raises)."""
        self.stop_reason = reason
        self.loop.stop()
        with contextlib.suppress(Exception):
            self.loop.tick_control(self.clock())

    def on_app_blur(self, event: events.AppBlur) -> None:
        self.stop_robot("terminal lost focus")

    def teleop_key(self, key: str) -> bool:
        """A key pressed on the control screen; True if teleop used it."""
        if self.loop.running and key in ("k", " ", "space"):
            self.loop.stop()
        was_manual = self.loop.algorithm == "manual"
        result = self.teleop.press(key, self.clock())
        if result is None:
            return False
        if result == "move" and not was_manual:
            # Manual keys take over from an autonomous controller.
            self.loop.set_algorithm("manual")
            self.teleop.press(key, self.clock())
        if result == "move":
            self.loop.running = False
            self._control_tick()  # respond to the first press at once, not at the next tick
        return True

    def get_system_commands(self, screen: Screen[object]) -> Iterable[SystemCommand]:
        yield from super().get_system_commands(screen)
        for name in self.MODES:
            yield SystemCommand(
                f"Screen: {name}", f"Switch to the {name} screen", lambda n=name: self.action_mode(n)
            )
        yield SystemCommand("Stop the robot", "Zero velocity now", lambda: self.stop_robot("palette"))
        yield SystemCommand("Start/stop collection", "Toggle analytics collection", self.toggle_collection)
        for fmt in ("csv", "json", "mcap"):
            yield SystemCommand(
                f"Export {fmt.upper()}", f"Write the collected data as {fmt}", lambda f=fmt: self.export(f)
            )

    # -- actions -------------------------------------------------------------------------------
    def action_mode(self, name: str) -> None:
        if name != self.current_mode:
            self.switch_mode(name)

    def action_help(self) -> None:
        if not isinstance(self.screen, HelpScreen):
            self.push_screen(HelpScreen())

    async def action_stop_and_quit(self) -> None:
        self.stop_robot("quit")
        self.exit()

    def toggle_collection(self) -> None:
        if self.store.is_collecting:
            self.store.stop_collection()
        else:
            self.store.start_collection()
        self._redraw()

    def export(self, fmt: str) -> str:
        try:
            path = export_store(self.store, fmt, self.settings.export_dir)
        except (ExportError, OSError, ValueError) as exc:
            self.export_message = f"EXPORT FAILED ({fmt}): {exc} — collected data kept"
            self.notify(self.export_message, severity="error", timeout=6)
        else:
            self.export_message = f"wrote {path} ({len(self.store)} points)"
            self.notify(self.export_message, timeout=4)
        return self.export_message

    # -- shared views ------------------------------------------------------------------------------
    def latency_view(self) -> LatencyView | None:
        if self.settings.mode == SIM or self.tracker is None:
            return None
        return self.tracker.view

    def link_down(self) -> bool:
        """The rosbridge link was lost (or never came up): nothing the console sends goes out."""
        return self.link.state in (DISCONNECTED, RECONNECTING)

    def status_text(self) -> str:
        link_state = self.link.state
        if link_state == RECONNECTING:
            link_state = "DISCONNECTED (reconnecting)"
        collecting = f"REC {len(self.store)}" if self.store.is_collecting else f"idle {len(self.store)}"
        tracker = ""
        if self.tracker is not None:
            reach = self.tracker.view.reachable
            tracker = " · api " + ("?" if reach is None else ("ok" if reach else "UNREACHABLE"))
        ports = ""
        if self.settings.mode == "embedded":
            bridge = self.settings.rosbridge_url.rsplit(":", 1)[-1]
            api = (self.settings.tracker_url or "").rsplit(":", 1)[-1]
            ports = f" {bridge}/{api}"
        return (
            f"{link_state} · {self.settings.mode}{ports} · deploy {self.deploy_mode()} · "
            f"{self.loop.algorithm} · {collecting}{tracker}"
        )

    def deploy_mode(self) -> str:
        if self.tracker is not None and self.tracker.view.reachable:
            return self.tracker.view.deploy_mode
        return self.settings.deploy_mode if self.settings.mode != SIM else "sim"


def make_app(
    settings: Settings,
    link: Link,
    tracker: TrackerClient | None = None,
    store: AnalyticsStore = STORE,
    clock: Callable[[], float] = time.monotonic,
) -> ArbiterApp:
    """Build the app for the CLI and for tests alike, with the links injected."""
    return ArbiterApp(settings, link, tracker=tracker, store=store, clock=clock)
