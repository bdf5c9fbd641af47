"""Control screen: keyboard teleop, algorithm and mission selection, goals (t, or a click on the map),
pose/errors and the live map. On a terminal of at least 160x45 it is the dashboard: the same control
panel and map (and the topics table beside them), with the live comparison and the link's latency below,
as the seed's web dashboard shows its performance cards beside control."""

from __future__ import annotations

from textual import events
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import Static

from arbiter_core.controllers import ALGORITHMS

from ...control.teleop import key_name
from ..perf.heap import freeze_heap
from ..widgets.analytics import CompareTable, RuleLine
from ..widgets.plots import ErrorPlot, LatencyHistogram, LatencyPlot, LiveMap, TrajectoryPlot
from ..widgets.text import FIT, KEY_HELP, ClientLine, RobotPanel, StatsCards, TrackerCards, TrackerLine
from ..widgets.topics import TopicsPane
from .base import PLOTTED, BaseScreen

DASHBOARD_WIDTH, DASHBOARD_HEIGHT = 160, 45
WIDE_PANEL = 100  # from this width the control panel is wide enough for every row's longest form
WIDE_WIDTH = 180  # the dashboard shows the trajectory and the latency histogram from this width on


class ControlScreen(BaseScreen):
    CSS_PATH = ["base.tcss", "control.tcss"]
    HORIZONTAL_BREAKPOINTS = [(0, "-narrow"), (WIDE_PANEL, "-wide")]  # the panel's width (control.tcss)
    BINDINGS = [
        Binding("a", "cycle_algorithm", "Algo"),
        Binding("n", "cycle_mission", "Mission"),
        Binding("g", "go", "Go"),
        Binding("G", "restart", "Restart", show=False),
        Binding("t", "goal", "Goal", show=False),  # in ? help and README: the footer fits in 80 columns
    ]
    dashboard = False  # the terminal is large enough for the dashboard (set on every resize)
    _dashboard_frozen = False

    def compose_body(self) -> ComposeResult:
        with Horizontal(id="drive"):
            with Vertical(id="panel"):
                yield RobotPanel(id="robot").data_bind(BaseScreen.frame)
                yield Static(KEY_HELP, id="keys")  # painted once: the legend never changes
            yield LiveMap("map (m)", id="map").data_bind(*PLOTTED)

    @staticmethod
    def dashboard_panes() -> tuple[TopicsPane, Horizontal]:
        """What the dashboard adds: the topics table beside the panel and the map, and below them the same
        widgets as screens 2 and 3, their figures laid out to their width (``FIT``) and their plots taking
        the rows left (two plots each from ``WIDE_WIDTH`` columns on). Each is bound to this screen's
        frame (called from the screen's own handler)."""
        frame = BaseScreen.frame
        table = CompareTable(id="dash-table", show_cursor=False, zebra_stripes=True).data_bind(frame)
        table.can_focus = False  # the arrow keys drive here: they must never scroll a table
        compare = Vertical(
            StatsCards(id="dash-cards", classes=FIT).data_bind(frame),
            table,
            RuleLine(id="dash-rule").data_bind(frame),
            Horizontal(
                ErrorPlot("e_d (m) vs time (s)", id="dash-err").data_bind(*PLOTTED),
                TrajectoryPlot("trajectory (m)", id="dash-traj").data_bind(*PLOTTED),
                id="dash-compare-plots",
            ),
            id="dash-compare",
        )
        latency = Vertical(
            TrackerLine(id="dash-lat-state", classes=FIT).data_bind(frame),
            TrackerCards(id="dash-lat-cards").data_bind(frame),
            ClientLine(id="dash-lat-client", classes=FIT).data_bind(frame),
            Horizontal(
                LatencyPlot("one-way (ms) vs time (s)", id="dash-lat-plot").data_bind(*PLOTTED),
                LatencyHistogram("one-way (ms) histogram", id="dash-lat-hist").data_bind(*PLOTTED),
                id="dash-lat-plots",
            ),
            id="dash-latency",
        )
        return TopicsPane(id="dash-topics").data_bind(frame), Horizontal(compare, latency, id="dash")

    def on_resize(self, event: events.Resize) -> None:
        # (Textual calls BaseScreen.on_resize too, after this: handlers run for each class)
        dashboard = event.size.width >= DASHBOARD_WIDTH and event.size.height >= DASHBOARD_HEIGHT
        if dashboard and not self.query("#dash"):
            # made the first time it is needed: a small terminal does not pay for it at start
            topics, panes = self.dashboard_panes()
            self.query_one("#drive").mount(topics)
            self.query_one("#body").mount(panes)
        self.set_class(dashboard and event.size.width >= WIDE_WIDTH, "dash-wide")
        if dashboard != self.dashboard:
            self.dashboard = dashboard
            self.set_class(dashboard, "dashboard")
            self.console.refresh_frame(force=True)  # its panes show what was not sampled before
            if dashboard and not self._dashboard_frozen:  # its widgets, once made, live for good
                self._dashboard_frozen = True
                self.call_after_refresh(freeze_heap)

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """Observe mode: the console runs no mission of its own; a, n and g pick and start the robot-side
        controller, and only where the backend runs one; no typed goal."""
        if not self.console.session.config.observe:
            return True
        if action in ("goal", "restart"):
            return False
        if action in ("cycle_algorithm", "cycle_mission", "go"):
            robot_side = self.frame.robot.robot_side
            return robot_side is not None and robot_side.enabled
        return True

    def on_key(self, event: events.Key) -> None:
        if self.console.session.key(key_name(event.character, event.key), self.console.keys.when(event)):
            self.console.refresh_frame()  # a new command or limit shows at once; a held key's repeats
            event.stop()  # ...wait for the UI tick
            event.prevent_default()

    def on_screen_resume(self) -> None:
        self.console.keys.set_direct(True)  # teleop keys may go to the session from the input thread

    def on_screen_suspend(self) -> None:
        self.console.keys.set_direct(False)
        # A held key must not keep the robot moving unseen; an autonomous run goes on (watch it live).
        self.console.session.end_manual_hold("left the control screen")

    def action_cycle_algorithm(self) -> None:
        session = self.console.session
        session.select_algorithm(ALGORITHMS[(ALGORITHMS.index(session.loop.algorithm) + 1) % len(ALGORITHMS)])
        self.console.refresh_frame(force=True)

    def action_cycle_mission(self) -> None:
        self.console.session.cycle_mission()
        self.console.refresh_frame()

    def action_go(self) -> None:
        self.console.go()

    def action_restart(self) -> None:
        self.console.go(restart=True)

    def action_goal(self) -> None:
        if not self.console.session.too_small:
            self.console.dialogs.ask_goal()
