"""Latency screen: the tracker's stats, a sparkline of its rolling window, recent records, and this
console's own round trip, clock offset and loss."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.widgets import DataTable, Sparkline

from ..views import LatencySnapshot
from ..widgets import ClientLine, TrackerCards, TrackerLine, fmt_ms
from .base import BaseScreen


class LatencySparkline(Sparkline):
    def on_mount(self) -> None:
        self._shown: tuple[int, int] | None = None
        self.watch(self.app, "latency", self._show)

    def _show(self, view: LatencySnapshot) -> None:
        key = (view.polled, view.failures)  # a poll brought something new (or failed)
        if key != self._shown:
            self._shown = key
            self.data = list(view.window)


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
        yield LatencySparkline([], id="lat-spark")
        yield RecordsTable(id="lat-records", show_cursor=False, zebra_stripes=True)
