"""Typing a go-to-goal target: ``x y`` in metres; enter drives there, escape cancels."""

from __future__ import annotations

from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.widgets import Footer, Input, Static

from arbiter_core.controllers import DEFAULT_CONTROLLER

from ...control.goals import GoalError, parse_goal
from ..keys import STOP_HINT_TYPING


class GoalPrompt(ModalScreen[tuple[float, float] | None]):
    CSS_PATH = "modal.tcss"
    BINDINGS = [Binding("escape", "cancel", "Cancel"), STOP_HINT_TYPING]

    def __init__(self, pose: tuple[float, float], driver: str = DEFAULT_CONTROLLER) -> None:
        super().__init__()
        self.pose = pose
        self.driver = driver  # the controller enter starts (arbiter_core.controllers.goal_driver)

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            yield Static(
                "Drive to x y (m, odometry frame). "
                f"The robot is at {self.pose[0]:+.2f} {self.pose[1]:+.2f}.\n"
                f"enter: drive there with {self.driver} · escape: cancel · ctrl+k: stop the robot"
            )
            yield Input(placeholder="x y, e.g. 1.5 -0.5", id="goal-input")
            yield Static("", id="goal-error")
        yield Footer(show_command_palette=False, compact=True)

    @on(Input.Submitted)
    def _submitted(self, event: Input.Submitted) -> None:
        try:
            goal = parse_goal(event.value)
        except GoalError as exc:
            self.query_one("#goal-error", Static).update(f"[b red]{exc}[/]")
            return
        self.dismiss(goal)

    def action_cancel(self) -> None:
        self.dismiss(None)
