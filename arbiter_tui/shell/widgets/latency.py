"""The latency screen's own widget: the newest records."""

from __future__ import annotations

from rich.text import Text
from textual.reactive import reactive

from ...session.frames import Frame
from ...session.views import LatencySnapshot
from .text import Bound, fmt_ms


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
