"""Export chooser: which format(s) to write the collected samples as."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen
from textual.widgets import Button, Footer, Static

from ..keys import STOP_HINT

CHOICES = {"csv": ("csv",), "json": ("json",), "mcap": ("mcap",), "all": ("csv", "json", "mcap")}


class ExportChooser(ModalScreen[tuple[str, ...] | None]):
    CSS_PATH = "modal.tcss"
    BINDINGS = [
        Binding("c", "choose('csv')", "CSV"),
        Binding("j", "choose('json')", "JSON"),
        Binding("m", "choose('mcap')", "MCAP"),
        Binding("a", "choose('all')", "All"),
        Binding("escape", "choose('')", "Cancel"),
        STOP_HINT,
    ]

    def __init__(self, points: int) -> None:
        super().__init__()
        self.points = points

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Static(f"Export {self.points} samples as:")
            with Horizontal(classes="buttons"):
                for name in CHOICES:
                    yield Button(f"{name.upper()} ({name[0]})", id=name)
        yield Footer(show_command_palette=False, compact=True)

    def on_button_pressed(self, event: Button.Pressed) -> None:
        self.action_choose(event.button.id or "")

    def action_choose(self, name: str) -> None:
        self.dismiss(CHOICES.get(name))
