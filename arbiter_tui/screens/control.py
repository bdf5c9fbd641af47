"""Control screen: keyboard teleop, algorithm and mission selection, pose/errors, trajectory map."""

from __future__ import annotations

import math

from rich.text import Text
from textual import events
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.widgets import Static

from ..control.teleop import legend_compact
from ..widgets import MapView
from .base import BaseScreen

KEY_HELP = legend_compact()


LINK_DOWN = (  # fits the 36 columns inside the panel
    "LINK DOWN: nothing is sent.\nThe robot stops on its own timeout.\nPress a key once the link is back.\n"
)


class ControlScreen(BaseScreen):
    DEFAULT_CSS = """
    ControlScreen #panel { width: 40; border: round $secondary; padding: 0 1; }
    ControlScreen #keys { height: auto; color: $text-muted; }
    """
    BINDINGS = [
        Binding("a", "cycle_algorithm", "Algorithm"),
        Binding("n", "cycle_mission", "Mission"),
        Binding("g", "go", "Go"),
    ]

    def compose_body(self) -> ComposeResult:
        with Horizontal():
            yield Static(id="panel")
            yield MapView(id="map")

    def on_key(self, event: events.Key) -> None:
        key = event.character if event.character and event.character.isprintable() else event.key
        if key is None:
            return
        if self.arbiter.teleop_key(key):
            event.stop()
            event.prevent_default()

    def on_screen_suspend(self) -> None:
        self.arbiter.stop_robot("left the control screen")

    def action_cycle_algorithm(self) -> None:
        self.arbiter.loop.cycle_algorithm()
        self.refresh_view()

    def action_cycle_mission(self) -> None:
        self.arbiter.loop.cycle_mission()
        self.refresh_view()

    def action_go(self) -> None:
        if not self.arbiter.loop.start_autonomous():
            self.app.notify("Select go_to_goal or pure_pursuit with [b]a[/b] first", severity="warning")
        self.refresh_view()

    def refresh_view(self) -> None:
        if not self.ready:
            return
        super().refresh_view()
        app = self.arbiter
        loop = app.loop
        pose, v_odom, w_odom, _lat = loop.link.telemetry.snapshot()
        e_d, e_th = loop.errors(pose)
        v, w = loop.command
        state = "driving" if loop.running else ("teleop" if loop.teleop.moving else "stopped")
        t = Text()
        if app.link_down():
            t.append(LINK_DOWN, "bold red")
        t.append("Command  ", "bold")
        t.append(f"v {v:+.2f} m/s  ω {w:+.2f} rad/s\n")
        t.append("Max      ", "bold")
        t.append(f"speed {loop.teleop.speed:.2f}  turn {loop.teleop.turn:.2f}\n")
        t.append("Pose     ", "bold")
        t.append(f"x {pose.x:+.2f} y {pose.y:+.2f} θ {math.degrees(pose.theta):+.0f}°\n")
        t.append("Odom     ", "bold")
        t.append(f"v {v_odom:+.2f}  ω {w_odom:+.2f}\n")
        t.append("Algo     ", "bold")
        t.append(f"{loop.algorithm} ({state})\n")
        t.append("Mission  ", "bold")
        done = len(loop.mission.waypoints) if loop.mission.done else loop.mission.index
        t.append(f"{loop.mission_name} {done}/{len(loop.mission.waypoints)}\n")
        t.append("Goal     ", "bold")
        gx, gy = loop.goal()
        t.append(f"({gx:+.2f}, {gy:+.2f})\n")
        t.append("Errors   ", "bold")
        t.append(f"e_d {e_d:.2f} m  e_θ {math.degrees(e_th):+.0f}°\n\n")
        t.append_text(Text.from_markup(KEY_HELP))
        self.query_one("#panel", Static).update(t)
        waypoints = loop.mission.waypoints if loop.algorithm != "manual" else []
        self.query_one("#map", MapView).show(list(loop.trail), pose, loop.goal(), waypoints)
