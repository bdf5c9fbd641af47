"""Analytics screen: collection control, the nine AnalyticsStats, per-algorithm comparison, plots, export."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import DataTable, Sparkline, Static

from ..analytics.labels import STAT_LABELS, format_stat
from ..analytics.store import STATS_FIELDS, AnalyticsStats
from ..widgets import MapView
from .base import BaseScreen

COMPARE = ("sampleCount", "avgDistanceError", "stdDevError", "p95Error", "avgHeadingError", "totalPathLength")


def stats_cards(stats: AnalyticsStats) -> Text:
    t = Text()
    for i, name in enumerate(STATS_FIELDS):
        t.append(f"{STAT_LABELS[name].short:>10} ", "bold")
        t.append(f"{format_stat(name, getattr(stats, name)):<16}")
        if i % 3 == 2 and i < len(STATS_FIELDS) - 1:
            t.append("\n")
    return t


class AnalyticsScreen(BaseScreen):
    DEFAULT_CSS = """
    AnalyticsScreen #cards { height: 3; border: none; padding: 0 1; }
    AnalyticsScreen #export-msg { height: 1; padding: 0 1; color: $text-muted; }
    AnalyticsScreen #compare { height: 6; }
    AnalyticsScreen #plots { height: 1fr; }
    AnalyticsScreen #traj { width: 1fr; }
    AnalyticsScreen #err-box { width: 1fr; border: round $primary; }
    AnalyticsScreen #err-spark { height: 1fr; }
    """
    BINDINGS = [
        Binding("r", "toggle_collect", "Start/stop"),
        Binding("x", "clear", "Clear"),
        Binding("c", "export('csv')", "CSV"),
        Binding("j", "export('json')", "JSON"),
        Binding("m", "export('mcap')", "MCAP"),
    ]

    def compose_body(self) -> ComposeResult:
        yield Static(id="cards")
        yield Static(id="export-msg")
        yield DataTable(id="compare", show_cursor=False, zebra_stripes=True)
        with Horizontal(id="plots"):
            yield MapView(id="traj")
            with Vertical(id="err-box"):
                yield Static("distance error over time", id="err-title")
                yield Sparkline([], id="err-spark")

    def on_mount(self) -> None:
        table = self.query_one("#compare", DataTable)
        table.add_columns("algorithm", *(STAT_LABELS[n].short for n in COMPARE))
        super().on_mount()

    def action_toggle_collect(self) -> None:
        self.arbiter.toggle_collection()

    def action_clear(self) -> None:
        self.arbiter.store.clear()
        self.arbiter.export_message = "cleared"
        self.refresh_view()

    def action_export(self, fmt: str) -> None:
        self.arbiter.export(fmt)
        self.refresh_view()

    def refresh_view(self) -> None:
        if not self.ready:
            return
        super().refresh_view()
        store = self.arbiter.store
        self.query_one("#cards", Static).update(stats_cards(store.stats()))
        self.query_one("#export-msg", Static).update(
            self.arbiter.export_message or "r start/stop · c/j/m export"
        )
        table = self.query_one("#compare", DataTable)
        table.clear()
        for algo, s in store.stats_by_algorithm().items():
            row = [algo] + [format_stat(n, getattr(s, n), decimals=3, unit=False) for n in COMPARE]
            table.add_row(*row)
        xs, ys = store.column("x", last=2000), store.column("y", last=2000)
        self.query_one("#traj", MapView).show(list(zip(xs.tolist(), ys.tolist(), strict=True)), None, None)
        self.query_one("#err-spark", Sparkline).data = store.column("distanceError", last=200).tolist()
