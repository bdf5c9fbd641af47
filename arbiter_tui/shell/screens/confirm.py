"""Clearing the collected samples asks first (nothing else in the console destroys data)."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen
from textual.widgets import Button, Footer, Static

from ..keys import STOP_HINT


class ConfirmClear(ModalScreen[bool]):
    CSS_PATH = "modal.tcss"
    BINDINGS = [
        Binding("y", "answer(True)", "Clear"),
        Binding("escape,n", "answer(False)", "Keep"),
        STOP_HINT,
    ]

    def __init__(self, points: int) -> None:
        super().__init__()
        self.points = points

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Static(f"Clear all {self.points} collected samples? This cannot be undone.")
            with Horizontal(classes="buttons"):
                yield Button("Keep them (n)", id="keep", variant="primary")
                yield Button("Clear (y)", id="clear", variant="error")
        yield Footer(show_command_palette=False, compact=True)

    def on_mount(self) -> None:
        self.query_one("#keep", Button).focus()  # enter keeps: the safe answer is the default

    def on_button_pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id == "clear")

    def action_answer(self, clear: bool) -> None:
        self.dismiss(clear)
