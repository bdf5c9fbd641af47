"""Latency screen: the tracker's stats, its latencies over time (with the p95) and their histogram,
recent records, and this console's own round trip, clock offset and loss."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.containers import Horizontal

from ..widgets.latency import RecordsList
from ..widgets.plots import LatencyHistogram, LatencyPlot
from ..widgets.text import FIT, ClientLine, TrackerCards, TrackerLine
from .base import PLOTTED, BaseScreen


class LatencyScreen(BaseScreen):
    CSS_PATH = ["base.tcss", "latency.tcss"]
    VERTICAL_BREAKPOINTS = [(0, "-short"), (30, "-tall")]  # below 30 rows the plots give way (latency.tcss)

    def compose_body(self) -> ComposeResult:
        # the lines of figures break between their parts, never between a label and its figure (FIT)
        yield TrackerLine(id="lat-state", classes=FIT).data_bind(BaseScreen.frame)
        yield TrackerCards(id="lat-cards").data_bind(BaseScreen.frame)
        yield ClientLine(id="lat-client", classes=FIT).data_bind(BaseScreen.frame)
        with Horizontal(id="lat-plots"):
            yield LatencyPlot("one-way (ms) vs time (s)", id="lat-plot").data_bind(*PLOTTED)
            yield LatencyHistogram("one-way (ms) histogram", id="lat-hist").data_bind(*PLOTTED)
        yield RecordsList(id="lat-records").data_bind(BaseScreen.frame)
