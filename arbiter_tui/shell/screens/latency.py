"""Latency screen: the tracker's stats, its latencies over time (with the p95) and their histogram,
recent records, and this console's own round trip, clock offset and loss."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Horizontal
from textual.reactive import reactive

from ...session.frames import Frame
from ...session.views import LatencySnapshot
from ..plots import LatencyHistogram, LatencyPlot
from ..widgets import FIT, Bound, ClientLine, TrackerCards, TrackerLine, fmt_ms
from .base import PLOTTED, BaseScreen


class RecordsList(Bound[LatencySnapshot]):
    """The newest records, as many as fit: plain lines, repainted only when a poll brought new ones.
    (A DataTable refilled at every poll was a third of this screen's CPU: bench/pi.py, py-spy.)"""

    view: reactive[LatencySnapshot] = reactive(LatencySnapshot)

    def pick(self, frame: Frame) -> LatencySnapshot:
        return frame.latency

    HEAD = f"{'seq':>8}  {'latency':>10}  {'linear_x':>8}  {'angular_z':>9}  mode"

    def draw(self) -> Text:
        rows = max(0, self.size.height - 1)
        out = Text(self.HEAD + "\n", style="bold")
        for r in self.view.records[:rows]:
            seq = "" if r.seq is None else str(r.seq)
            lat = fmt_ms(r.latency_ms)
            out.append(f"{seq:>8}  {lat:>10}  {r.linear_x:>+8.2f}  {r.angular_z:>+9.2f}  {r.deploy_mode}\n")
        return out


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
