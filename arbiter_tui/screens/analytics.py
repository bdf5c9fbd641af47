"""Analytics screen: collection control, the nine AnalyticsStats, per-algorithm comparison, plots, export.

None of its keys is a teleop letter: clearing asks first, exporting opens a chooser.
"""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import DataTable, Sparkline, Static

from ..analytics.labels import STAT_LABELS, format_stat
from ..views import AnalyticsView
from ..widgets import AnalyticsTrail, StatsCards
from .base import BaseScreen

COMPARE = ("sampleCount", "avgDistanceError", "stdDevError", "p95Error", "avgHeadingError", "totalPathLength")


class CompareTable(DataTable[str]):
    """Per-algorithm stats; refilled only when the per-algorithm figures changed."""

    def on_mount(self) -> None:
        self.add_columns("algorithm", *(STAT_LABELS[n].short for n in COMPARE))
        self._shown: tuple[object, ...] | None = None
        self.watch(self.app, "analytics", self._show)

    def _show(self, view: AnalyticsView) -> None:
        if view.by_algorithm == self._shown:
            return
        self._shown = view.by_algorithm
        self.clear()
        for algo, s in view.by_algorithm:
            self.add_row(algo, *(format_stat(n, getattr(s, n), decimals=3, unit=False) for n in COMPARE))


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
        yield CompareTable(id="compare", show_cursor=False, zebra_stripes=True)
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
