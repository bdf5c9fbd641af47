"""Control screen: keyboard teleop, algorithm and mission selection, pose/errors, trajectory map."""

from __future__ import annotations

from textual import events
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import Static

from ..widgets import KEY_HELP, RobotPanel, TrajectoryMap
from .base import BaseScreen


class ControlScreen(BaseScreen):
    CSS_PATH = ["base.tcss", "control.tcss"]
    BINDINGS = [
        Binding("a", "cycle_algorithm", "Algo"),
        Binding("n", "cycle_mission", "Mission"),
        Binding("g", "go", "Go"),
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
        self.arbiter.loop.cycle_algorithm()
        self.arbiter.publish_views()

    def action_cycle_mission(self) -> None:
        self.arbiter.loop.cycle_mission()
        self.arbiter.publish_views()

    def action_go(self) -> None:
        if self.arbiter.too_small:
            return  # nothing starts moving while the console cannot be seen
        if not self.arbiter.loop.start_autonomous():
            self.app.notify("Select go_to_goal or pure_pursuit with [b]a[/b] first", severity="warning")
        self.arbiter.publish_views()
