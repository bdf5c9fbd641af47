"""What every screen shares: the status line on top, the footer, and the "terminal too small" guard."""

from __future__ import annotations

from typing import Protocol, cast

from textual import events
from textual.app import ComposeResult
from textual.containers import Container
from textual.geometry import Size
from textual.screen import Screen
from textual.widgets import Footer, Static

from ...analytics.store import AnalyticsStore
from ...control.loop import ControlLoop
from ...session.robot import ExportResult
from ..widgets import StatusLine


class Console(Protocol):
    """What the screens ask of the console (the app implements it): session commands that also refresh
    what is shown, and the dialogs. Screens never reach into the concrete app."""

    @property
    def loop(self) -> ControlLoop: ...

    @property
    def store(self) -> AnalyticsStore: ...

    @property
    def too_small(self) -> bool: ...

    def publish_views(self, force: bool = False) -> None: ...

    def screen_shown(self, name: str | None = None) -> None: ...

    def set_too_small(self, small: bool) -> None: ...

    def teleop_key(self, key: str) -> bool: ...

    def set_keys_direct(self, direct: bool) -> None: ...

    def end_manual_hold(self, reason: str) -> None: ...

    def select_algorithm(self, name: str) -> None: ...

    def cycle_mission(self) -> None: ...

    def go(self, restart: bool = False) -> bool: ...

    def ask_goal(self) -> None: ...

    def toggle_collection(self) -> None: ...

    def ask_clear(self) -> None: ...

    def export(self, *formats: str) -> list[ExportResult]: ...

    def echo_topic(self, name: str | None) -> None: ...


MIN_WIDTH, MIN_HEIGHT = 80, 24
TOO_SMALL = (
    f"Terminal too small: need at least {MIN_WIDTH}x{MIN_HEIGHT}. The robot is stopped and movement "
    "keys are ignored until the window is larger (ctrl+q quits)."
)


class BaseScreen(Screen[None]):
    CSS_PATH = "base.tcss"

    @property
    def arbiter(self) -> Console:
        return cast(Console, self.app)

    def compose(self) -> ComposeResult:
        yield StatusLine(id="status")
        yield Static(TOO_SMALL, id="too-small")
        with Container(id="body"):
            yield from self.compose_body()
        # ctrl+p stays bound (and listed in ? help); not shown, so the footer fits in 80 columns
        yield Footer(show_command_palette=False, compact=True)

    def compose_body(self) -> ComposeResult:
        yield from ()

    def on_mount(self) -> None:
        self._check_size(self.app.size)

    def on_screen_resume(self) -> None:
        self._check_size(self.app.size)
        self.arbiter.publish_views(force=True)  # what it shows may not have been sampled meanwhile
        self.arbiter.screen_shown()

    def on_resize(self, event: events.Resize) -> None:
        self._check_size(event.size)

    def _check_size(self, size: Size) -> None:
        small = size.width < MIN_WIDTH or size.height < MIN_HEIGHT
        self.set_class(small, "too-small")
        if small != self.arbiter.too_small:
            self.arbiter.set_too_small(small)
