"""Latency screen: the tracker's stats, its latencies over time (with the p95) and their histogram,
recent records, and this console's own round trip, clock offset and loss."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.containers import Horizontal
from textual.widgets import DataTable

from ..plots import LatencyHistogram, LatencyPlot
from ..views import LatencySnapshot
from ..widgets import ClientLine, TrackerCards, TrackerLine, fmt_ms
from .base import BaseScreen


class RecordsTable(DataTable[str]):
    """The newest records; refilled only when a poll brought new ones."""

    def on_mount(self) -> None:
        self.add_columns("seq", "latency", "linear_x", "angular_z", "mode")
        self._shown: int | None = None
        self.watch(self.app, "latency", self._show)

    def _show(self, view: LatencySnapshot) -> None:
        if view.polled == self._shown:
            return
        self._shown = view.polled
        self.clear()
        for r in view.records:
            self.add_row(
                "" if r.seq is None else str(r.seq),
                fmt_ms(r.latency_ms),
                f"{r.linear_x:+.2f}",
                f"{r.angular_z:+.2f}",
                r.deploy_mode,
            )


class LatencyScreen(BaseScreen):
    CSS_PATH = ["base.tcss", "latency.tcss"]

    def compose_body(self) -> ComposeResult:
        yield TrackerLine(id="lat-state")
        yield TrackerCards(id="lat-cards")
        yield ClientLine(id="lat-client")
        with Horizontal(id="lat-plots"):
            yield LatencyPlot("one-way (ms) vs time (s)", id="lat-plot")
            yield LatencyHistogram("one-way (ms) histogram", id="lat-hist")
        yield RecordsTable(id="lat-records", show_cursor=False, zebra_stripes=True)
