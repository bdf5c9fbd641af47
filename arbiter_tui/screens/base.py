"""What every screen shares: the status line on top, the footer, and the "terminal too small" guard."""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

from textual import events
from textual.app import ComposeResult
from textual.containers import Container
from textual.screen import Screen
from textual.widgets import Footer, Static

from ..widgets import StatusLine

if TYPE_CHECKING:
    from ..app import ArbiterApp

MIN_WIDTH, MIN_HEIGHT = 80, 24


class BaseScreen(Screen[None]):
    DEFAULT_CSS = """
    #too-small { display: none; width: 100%; height: 100%; content-align: center middle; text-style: bold; }
    BaseScreen.too-small #too-small { display: block; }
    BaseScreen.too-small #body { display: none; }
    #body { height: 1fr; }
    """

    @property
    def arbiter(self) -> ArbiterApp:
        return cast("ArbiterApp", self.app)

    def compose(self) -> ComposeResult:
        yield StatusLine(id="status")
        yield Static(
            f"Terminal too small: need at least {MIN_WIDTH}x{MIN_HEIGHT}. Enlarge the window (ctrl+q quits).",
            id="too-small",
        )
        with Container(id="body"):
            yield from self.compose_body()
        yield Footer()

    def compose_body(self) -> ComposeResult:
        yield from ()

    def on_mount(self) -> None:
        self._mounted_once = True
        self._check_size(self.app.size.width, self.app.size.height)
        self.refresh_view()

    def on_screen_resume(self) -> None:
        self._check_size(self.app.size.width, self.app.size.height)
        self.refresh_view()

    def on_resize(self, event: events.Resize) -> None:
        self._check_size(event.size.width, event.size.height)

    def _check_size(self, width: int, height: int) -> None:
        self.set_class(width < MIN_WIDTH or height < MIN_HEIGHT, "too-small")

    _mounted_once = False

    @property
    def ready(self) -> bool:
        """False until on_mount ran: the app's redraw timer can reach a screen made current just before."""
        return self._mounted_once

    def refresh_view(self) -> None:
        """Redraw from the shared state (called by the app at its fixed UI rate)."""
        status = self.query_one("#status", StatusLine)
        status.update(self.arbiter.status_text())
        status.set_class(self.arbiter.link_down(), "alarm")
