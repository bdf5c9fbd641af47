"""The Textual app: three modes (control, analytics, latency) over one store, one link, one poller."""

from __future__ import annotations

import asyncio
import contextlib
import signal
import time
from collections.abc import Callable

from textual import events
from textual.app import App
from textual.binding import Binding

from arbiter_backend.core.analytics import STORE, AnalyticsStore
from arbiter_backend.files import ExportError, export_store

from .control_loop import ControlLoop
from .links import Link, SimLink
from .screens.analytics import AnalyticsScreen
from .screens.control import ControlScreen
from .screens.help import HelpScreen
from .screens.latency import LatencyScreen
from .settings import SIM, Settings
from .teleop import Teleop
from .tracker_client import LatencyView, TrackerClient


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
            self.set_interval(1.0 / self.store.collection_rate, self.loop.sample)
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
        self.exit()

    async def _poll_forever(self) -> None:
        assert self.tracker is not None
        period = self.settings.poll_period
        while True:
            started = time.monotonic()
            await self.tracker.poll()
            await asyncio.sleep(max(0.0, period - (time.monotonic() - started)))

    def _control_tick(self) -> None:
        self.loop.tick_control(self.clock())

    def _redraw(self) -> None:
        screen = self.screen
        refresh = getattr(screen, "refresh_view", None)
        if refresh is not None:
            refresh()

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

    def status_text(self) -> str:
        link_state = self.link.state
        collecting = (
            f"REC {len(self.store)} pts" if self.store.is_collecting else f"idle {len(self.store)} pts"
        )
        tracker = ""
        if self.tracker is not None:
            reach = self.tracker.view.reachable
            tracker = " · tracker " + ("?" if reach is None else ("ok" if reach else "UNREACHABLE"))
        return (
            f"{link_state} · {self.settings.mode} · deploy {self.deploy_mode()} · "
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
