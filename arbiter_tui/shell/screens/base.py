"""What every screen shares: the status line on top, the footer, the "terminal too small" guard, and
the frame every widget on it shows (``frame``: widgets take it with ``data_bind`` and pick their part).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar, Protocol, runtime_checkable

from rich.text import Text
from textual import events
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Container
from textual.geometry import Size
from textual.reactive import reactive
from textual.screen import Screen
from textual.widgets import Footer, Static

from arbiter_core import topics

from ...session.frames import Frame
from ...session.robot import RobotSession
from ...session.views import observe_banner
from ..keys import KeyRouter
from ..perf.heap import freeze_heap
from ..widgets.plots import PlotBudget
from ..widgets.text import StatusLine

if TYPE_CHECKING:  # the dialogs are above the screens: named here, never imported at run time
    from textual._path import CSSPathType

    from ..dialogs import Dialogs


@runtime_checkable
class Console(Protocol):
    """What the screens ask of the console (the app implements it): the robot session, which they call
    directly, a fresh frame after they did, and what needs the app (dialogs, notices, the key router)."""

    @property
    def session(self) -> RobotSession: ...

    @property
    def keys(self) -> KeyRouter: ...

    def refresh_frame(self, force: bool = False) -> None:
        """Show what just changed: a new frame now (``force``: past every rate gate)."""

    def go(self, restart: bool = False) -> bool:
        """Resume or start the selected mission (``restart``: from its first waypoint); False, with a
        notice saying why, if it cannot."""

    @property
    def dialogs(self) -> Dialogs:
        """What the console asks the user (``shell/dialogs.py``): screens reach dialogs through it."""


MIN_WIDTH, MIN_HEIGHT = 80, 24
TOO_SMALL = (
    f"Terminal too small: need at least {MIN_WIDTH}x{MIN_HEIGHT}. The robot is stopped and movement "
    "keys are ignored until the window is larger (ctrl+q quits)."
)


class BaseScreen(Screen[None]):
    CSS_PATH: ClassVar[CSSPathType | None] = "base.tcss"
    # R, on every screen: the journal of a session that did not end cleanly (said at start), on screen 2
    BINDINGS: ClassVar[list[BindingType]] = [Binding("R", "open_journal", "Journal", show=False)]
    # the latest frame: set by the app for the screens it shows, bound (data_bind) into every widget
    frame: reactive[Frame] = reactive(Frame, repaint=False, always_update=True)
    _console_app: Console | None = None  # not _console: Textual's Widget has one (the Rich console)
    _frozen = False  # its widgets, made on its first showing, are out of the collector's way
    # the plot redraws each frame allows, handed down to its plots (data_bind), renewed by the app
    plot_budget: reactive[PlotBudget] = reactive(PlotBudget, repaint=False)

    @property
    def console(self) -> Console:
        if self._console_app is None:
            app = self.app
            if not isinstance(app, Console):
                raise TypeError(f"{type(self).__name__} needs a console app, not {type(app).__name__}")
            self._console_app = app
        return self._console_app

    def compose(self) -> ComposeResult:
        yield StatusLine(id="status").data_bind(BaseScreen.frame)
        yield Static(id="observe-banner")  # observe mode only (on_mount): what drives and what a stop does
        yield Static(TOO_SMALL, id="too-small")
        with Container(id="body"):
            yield from self.compose_body()
        # ctrl+p stays bound (and listed in ? help); not shown, so the footer fits in 80 columns
        yield Footer(show_command_palette=False, compact=True)

    def compose_body(self) -> ComposeResult:
        yield from ()

    def on_mount(self) -> None:
        self._check_size(self.app.size)
        session = self.console.session
        config = session.config
        if config.observe:
            names = (config.odom_topic, config.cmd_topic, config.plan_topic, config.goal_topic)
            watched = [topics.resolve(t, config.namespace) for t in names]
            banner = observe_banner(config.observe_label, watched, session.stop_scope)
            self.query_one("#observe-banner", Static).update(Text(banner))
            self.add_class("observing")

    def action_open_journal(self) -> None:
        journal = self.console.session.journal
        found = None if journal is None else journal.offered
        if found is None:
            self.notify("no journal to open: the start found no session that ended uncleanly", timeout=4)
            return
        self.app.switch_mode("analytics")
        self.console.dialogs.open_path(found.path)

    def on_screen_resume(self) -> None:
        self._check_size(self.app.size)
        self.console.refresh_frame(force=True)  # what it shows may not have been sampled meanwhile
        self.freeze_once()

    def freeze_once(self) -> None:
        """After this screen's first showing, its widgets (kept for good) leave the collector's walks."""
        if not self._frozen:
            self._frozen = True
            self.call_after_refresh(freeze_heap)

    def on_resize(self, event: events.Resize) -> None:
        self._check_size(event.size)

    def _check_size(self, size: Size) -> None:
        small = size.width < MIN_WIDTH or size.height < MIN_HEIGHT
        self.set_class(small, "too-small")
        session = self.console.session
        if small != session.too_small:
            session.set_too_small(small)
            self.console.refresh_frame()


# what every plot binds: the frame it shows and the screen's plot budget it spends
PLOTTED = (BaseScreen.frame, BaseScreen.plot_budget)
