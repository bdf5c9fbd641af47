"""Typing a go-to-goal target: ``x y`` in metres; enter drives there (a goal far from the robot is asked
about first: enter again), escape cancels. It says where the robot is, live."""

from __future__ import annotations

from collections.abc import Callable

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.widgets import Footer, Input, Static

from arbiter_core.controllers import DEFAULT_CONTROLLER

from ...control.goals import GoalError, far_goal, parse_goal
from ..keys import STOP_HINT_TYPING


class GoalPrompt(ModalScreen[tuple[float, float] | None]):
    CSS_PATH = "modal.tcss"
    BINDINGS = [Binding("escape", "cancel", "Cancel"), STOP_HINT_TYPING]
    WHERE_S = 0.5  # how often it reads where the robot is (it may drive while one types)

    def __init__(self, where: Callable[[], tuple[float, float]], driver: str = DEFAULT_CONTROLLER) -> None:
        super().__init__()
        self.where = where  # where the robot is now: said live, and far goals measured from it
        self.driver = driver  # the controller enter starts (arbiter_core.controllers.goal_driver)
        self._asked: tuple[float, float] | None = None  # a far goal asked about (drawn): enter again drives
        self._said = ""

    def _what(self) -> str:
        x, y = self.where()
        return (
            f"Drive to x y (m, odometry frame). The robot is at {x:+.2f} {y:+.2f}.\n"
            f"enter: drive there with {self.driver} · escape: cancel · ctrl+k: stop the robot"
        )

    def compose(self) -> ComposeResult:
        with Vertical(classes="dialog"):
            self._said = self._what()
            yield Static(self._said, id="goal-what")
            yield Input(placeholder="x y, e.g. 1.5 -0.5", id="goal-input")
            yield Static("", id="goal-error")
        yield Footer(show_command_palette=False, compact=True)

    def on_mount(self) -> None:
        self.set_interval(self.WHERE_S, self._where)

    def _where(self) -> None:
        """The robot's position as it is now (repainted only when the text changed)."""
        said = self._what()
        if said != self._said:
            self._said = said
            self.query_one("#goal-what", Static).update(said)

    @on(Input.Submitted)
    def _submitted(self, event: Input.Submitted) -> None:
        try:
            goal = parse_goal(event.value)
        except GoalError as exc:
            self.query_one("#goal-error", Static).update(f"[b red]{exc}[/]")
            return
        far = far_goal(goal, self.where())
        if far is not None and goal != self._asked:  # far away: asked first, driven on a second enter
            self._asked = None  # ...once the question is on the screen: an enter typed ahead is no answer
            self.query_one("#goal-error", Static).update(Text(far, style="bold yellow"))
            self.call_after_refresh(self._shown, goal)
            return
        self.dismiss(goal)

    def _shown(self, goal: tuple[float, float]) -> None:
        """The far goal's question was drawn: the next enter answers it."""
        self._asked = goal

    def action_cancel(self) -> None:
        self.dismiss(None)
