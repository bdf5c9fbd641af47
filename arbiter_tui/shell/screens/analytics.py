"""Analytics screen: the seed's nine stats, the ranked comparison (per algorithm or per run), the
ring-buffer warning, and plots of the trajectory and the distance error over time.

None of its keys is a teleop letter: clearing asks first, exporting opens a chooser. ``f`` opens a
recording (a ros2 bag or an export) shown instead of the live session, marked as a file, until ``escape``.
"""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.geometry import Size

from ...analytics import table as T
from ...session.frames import Frame
from ..widgets.analytics import CompareTable, EmptyState, FileBanner, LinkLine, RingWarning, RuleLine
from ..widgets.plots import ErrorPlot, LinkPlot, TrajectoryPlot
from ..widgets.text import StatsCards
from .base import PLOTTED, BaseScreen

LINK_PLOT_WIDTH = 120  # the error-vs-latency plot from this width on
SHORT_HEIGHT = 30  # below it the plots keep 10 rows and the table above them scrolls (analytics.tcss)


class AnalyticsScreen(BaseScreen):
    CSS_PATH = ["base.tcss", "analytics.tcss"]
    VERTICAL_BREAKPOINTS = [(0, "-short"), (SHORT_HEIGHT, "-tall")]  # below: the plots keep their rows
    BINDINGS = [
        Binding("r", "toggle_collect", "Rec"),
        Binding("v", "toggle_view", "Runs"),
        Binding("s", "cycle_sort", "Sort", show=False),  # in ? help; clicking a header sorts too
        Binding("ctrl+s", "export", "Export"),
        Binding("delete", "clear", "Clear", show=False),  # in ? help and the palette (asks first)
        Binding("f", "open_file", "File", show=False),  # in ? help, the README and the palette
        Binding("escape", "live", "Live", tooltip="Back to the live session"),
    ]

    def compose_body(self) -> ComposeResult:
        yield FileBanner(id="file-banner").data_bind(BaseScreen.frame)
        yield StatsCards(id="cards").data_bind(BaseScreen.frame)
        yield EmptyState(id="empty").data_bind(BaseScreen.frame)
        yield RingWarning(id="ring-warning").data_bind(BaseScreen.frame)
        yield CompareTable(id="compare", show_cursor=False, zebra_stripes=True).data_bind(BaseScreen.frame)
        yield RuleLine(id="rule").data_bind(BaseScreen.frame)
        with Horizontal(id="plots"):
            yield TrajectoryPlot("trajectory (m)", id="traj").data_bind(*PLOTTED)
            yield ErrorPlot("e_d (m) vs time (s)", id="err-plot").data_bind(*PLOTTED)
            yield LinkPlot("avg e_xt (m) vs latency (ms)", id="link-plot").data_bind(*PLOTTED)
        yield LinkLine(id="link-line").data_bind(BaseScreen.frame)

    def _check_size(self, size: Size) -> None:
        super()._check_size(size)
        # the error-vs-latency plot only where the other two keep room for their legends; its line of
        # text (the measured latency on the curve) is always shown
        self.set_class(size.width < LINK_PLOT_WIDTH, "no-link-plot")
        self.query_one(RingWarning).short = size.height < SHORT_HEIGHT

    def action_toggle_collect(self) -> None:
        self.console.session.toggle_collection()
        self.console.refresh_frame(force=True)

    def action_toggle_view(self) -> None:
        table = self.query_one(CompareTable)
        table.mode = T.BY_RUN if table.mode == T.BY_ALGORITHM else T.BY_ALGORITHM

    def action_cycle_sort(self) -> None:
        table = self.query_one(CompareTable)
        keys = [T.RANK, *table.table.keys]
        table.sort_by(keys[(keys.index(table.sort) + 1) % len(keys)] if table.sort in keys else T.RANK)
        table.descending = False

    def action_clear(self) -> None:
        self.console.dialogs.ask_clear()

    def action_open_file(self) -> None:
        self.console.dialogs.open_recording()

    def action_live(self) -> None:
        self.console.dialogs.live_session()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """``escape`` is offered only while a file is shown."""
        if action == "live":
            return bool(self.frame.analytics.source)
        return True

    def watch_frame(self, old: Frame, new: Frame) -> None:
        if bool(old.analytics.source) != bool(new.analytics.source):
            self.refresh_bindings()  # the footer offers esc only while a file is shown
            self.set_class(bool(new.analytics.source), "-file")  # no live latency over a file

    def action_export(self) -> None:
        self.console.dialogs.ask_export()
