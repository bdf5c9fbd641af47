#!/usr/bin/env python
"""The yardstick for bench/tui.py: the least Textual app of the console's shape.

A status line, a Static of figures and a Sparkline updated at 5 Hz, and a Footer; every key is
received and counted (as the console receives teleop keys). Nothing else, and each part as small as
it can be while still doing that (issue 48: the figures three rows, the sparkline one; a taller
sparkline, redrawn whole as it scrolls, wrote 72 KB/s where this writes about 15): what arbiter-tui costs
beyond this is the cost of its own work.
"""

from __future__ import annotations

import math
import time

from textual.app import App, ComposeResult
from textual.binding import Binding
from textual.widgets import Footer, Sparkline, Static


class BareApp(App[None]):
    CSS = """
    #status { dock: top; height: 1; background: $panel; padding: 0 1; }
    #figures { height: 3; padding: 0 1; }
    #spark { height: 1; }
    """
    BINDINGS = [Binding("ctrl+q", "quit", "Quit", priority=True), Binding("question_mark", "bell", "Help")]

    def compose(self) -> ComposeResult:
        yield Static("bare ready", id="status")
        yield Static(id="figures")
        yield Sparkline([], id="spark")
        yield Footer()

    def on_mount(self) -> None:
        self.keys = 0
        self.t0 = time.monotonic()
        self.values: list[float] = []
        self.set_interval(0.2, self.tick)

    def on_key(self) -> None:
        self.keys += 1

    def tick(self) -> None:
        t = time.monotonic() - self.t0
        self.values = [*self.values[-199:], math.sin(t) + 1.5]
        self.query_one("#figures", Static).update(
            f"t {t:8.2f} s   keys {self.keys}\nv {math.sin(t):+.2f} m/s  ω {math.cos(t):+.2f} rad/s\n"
            f"x {t % 7:+.2f} y {t % 5:+.2f} θ {t % 3:+.2f} rad"
        )
        self.query_one("#spark", Sparkline).data = self.values


if __name__ == "__main__":
    BareApp().run()
