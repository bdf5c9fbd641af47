"""Analytics screen: collection control, the nine AnalyticsStats, per-algorithm comparison, plots, export.

None of its keys is a teleop letter: clearing asks first, exporting opens a chooser.
"""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.reactive import reactive
from textual.widgets import Sparkline, Static

from ..analytics.labels import STAT_LABELS, format_stat
from ..views import AnalyticsView
from ..widgets import AnalyticsTrail, Bound, StatsCards
from .base import BaseScreen

COMPARE = ("sampleCount", "avgDistanceError", "stdDevError", "p95Error", "avgHeadingError", "totalPathLength")


class CompareTable(Bound):
    """Per-algorithm stats as aligned text: redrawn only when the per-algorithm figures changed."""

    SOURCE = "analytics"
    view: reactive[AnalyticsView] = reactive(AnalyticsView, repaint=False)
    _shown: tuple[object, ...] | None = None

    def watch_view(self, view: AnalyticsView) -> None:
        if view.by_algorithm != self._shown:
            self._shown = view.by_algorithm
            self.refresh()

    def draw(self) -> Text:
        rows = [["algorithm", *(STAT_LABELS[n].short for n in COMPARE)]]
        for algo, s in self.view.by_algorithm:
            rows.append([algo, *(format_stat(n, getattr(s, n), decimals=3, unit=False) for n in COMPARE)])
        widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]))]
        t = Text(no_wrap=True, overflow="crop")
        for k, row in enumerate(rows):
            line = "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True))
            t.append(line, "bold" if k == 0 else "")
            if k < len(rows) - 1:
                t.append("\n")
        return t


class ErrorSparkline(Sparkline):
    def on_mount(self) -> None:
        self.watch(self.app, "analytics", self._show)

    def _show(self, view: AnalyticsView) -> None:
        self.data = list(view.errors)


class AnalyticsScreen(BaseScreen):
    CSS_PATH = ["base.tcss", "analytics.tcss"]
    BINDINGS = [
        Binding("r", "toggle_collect", "Rec"),
        Binding("ctrl+s", "export", "Export"),
        Binding("delete", "clear", "Clear"),
    ]

    def compose_body(self) -> ComposeResult:
        yield StatsCards(id="cards")
        yield CompareTable(id="compare")
        with Horizontal(id="plots"):
            yield AnalyticsTrail(id="traj")
            with Vertical(id="err-box"):
                yield Static("distance error over time", id="err-title")
                yield ErrorSparkline([], id="err-spark")

    def action_toggle_collect(self) -> None:
        self.arbiter.toggle_collection()

    def action_clear(self) -> None:
        self.arbiter.ask_clear()

    def action_export(self) -> None:
        from .export import ExportChooser

        def chosen(formats: tuple[str, ...] | None) -> None:
            for fmt in formats or ():
                self.arbiter.export(fmt)

        self.app.push_screen(ExportChooser(len(self.arbiter.store)), chosen)
