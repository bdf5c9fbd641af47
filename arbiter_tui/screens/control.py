"""Control screen: keyboard teleop, algorithm and mission selection, goals (t, or a click on the map),
pose/errors, trajectory map."""

from __future__ import annotations

from textual import events
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import Static

from ..control.algorithms import ALGORITHMS
from ..widgets import KEY_HELP, RobotPanel, TrajectoryMap
from .base import BaseScreen


class ControlScreen(BaseScreen):
    CSS_PATH = ["base.tcss", "control.tcss"]
    BINDINGS = [
        Binding("a", "cycle_algorithm", "Algo"),
        Binding("n", "cycle_mission", "Mission"),
        Binding("g", "go", "Go"),
        Binding("G", "restart", "Restart", show=False),
        Binding("t", "goal", "Goal"),
    ]

    def compose_body(self) -> ComposeResult:
        with Horizontal():
            with Vertical(id="panel"):
                yield RobotPanel(id="robot")
                yield Static(KEY_HELP, id="keys")  # painted once: the legend never changes
            yield TrajectoryMap(id="map")

    def on_key(self, event: events.Key) -> None:
        key = event.character if event.character and event.character.isprintable() else event.key
        if key is None:
            return
        if self.arbiter.teleop_key(key):
            event.stop()
            event.prevent_default()

    def on_screen_suspend(self) -> None:
        # A held key must not keep the robot moving unseen; an autonomous run goes on (watch it live).
        self.arbiter.end_manual_hold("left the control screen")

    def action_cycle_algorithm(self) -> None:
        loop = self.arbiter.loop
        self.arbiter.select_algorithm(ALGORITHMS[(ALGORITHMS.index(loop.algorithm) + 1) % len(ALGORITHMS)])

    def action_cycle_mission(self) -> None:
        self.arbiter.cycle_mission()

    def action_go(self) -> None:
        self.arbiter.go()

    def action_restart(self) -> None:
        self.arbiter.go(restart=True)

    def action_goal(self) -> None:
        if not self.arbiter.too_small:
            self.arbiter.ask_goal()
