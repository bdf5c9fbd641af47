"""Opening a recording on the analytics screen: a path (→ completes it), enter opens, escape cancels."""

from __future__ import annotations

from pathlib import Path

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.widgets import Footer, Input, Static

from ..keys import STOP_HINT_TYPING
from ..paths import PathSuggester

WHAT = (
    "Open a recording: a ros2 bag (its directory, or a lone .mcap or .db3) or an arbiter export (CSV, JSON"
    " or MCAP). Its runs are ranked and plotted as `arbiter-tui stats` grades them, instead of the live "
    "session's, until escape on the analytics screen.\n→ completes · enter opens · escape cancels · ctrl+k "
    "stops the robot"
)


class OpenRecording(ModalScreen[Path | None]):
    CSS_PATH = "modal.tcss"
    BINDINGS = [Binding("escape", "cancel", "Cancel"), STOP_HINT_TYPING]

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Static(Text(WHAT))
            example = "path, e.g. ~/bags/rosbag2_2026_11_24"
            yield Input(placeholder=example, id="path", suggester=PathSuggester())
            yield Static("", id="path-error")
        yield Footer(show_command_palette=False, compact=True)

    @on(Input.Submitted)
    def _submitted(self, event: Input.Submitted) -> None:
        path = Path(event.value.strip()).expanduser()
        if not event.value.strip():
            return
        if not path.exists():
            said = Text(f"no such file or directory: {path}", style="bold red")
            self.query_one("#path-error", Static).update(said)
            return
        self.dismiss(path)

    def action_cancel(self) -> None:
        self.dismiss(None)
