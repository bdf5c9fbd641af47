"""Widgets that show one snapshot each (``views.py``): a reactive ``view``, rendered only when it changed.

Each widget names the app attribute it shows (``SOURCE``) and watches it; Textual compares the new
snapshot with the old and calls nothing when they are equal, so a widget whose data did not change
does no work. ``renders`` counts render calls (tests check that equal data costs nothing).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from rich.text import Text
from textual import events
from textual.geometry import Size
from textual.reactive import reactive
from textual.widget import Widget

from .analytics.labels import STAT_LABELS, format_stat
from .analytics.store import STATS_FIELDS
from .control.teleop import legend_compact
from .latency.clocksync import OffsetEstimate
from .messages import GoalPicked
from .views import AnalyticsView, LatencySnapshot, MapView, RobotView, StatusView

ARROWS = "→↗↑↖←↙↓↘"
LINK_DOWN = (  # fits the 36 columns inside the panel
    "LINK DOWN: nothing is sent.\nThe robot stops on its own timeout.\nPress a key once the link is back.\n"
)
KEY_HELP = legend_compact()


class Bound(Widget):
    """A widget that shows the app attribute named ``SOURCE`` (a frozen snapshot)."""

    SOURCE: ClassVar[str] = ""
    renders = 0

    def on_mount(self) -> None:
        self.watch(self.app, self.SOURCE, self._receive, init=True)

    def _receive(self, value: Any) -> None:
        self.view = value  # type: ignore[attr-defined]  # a reactive on each subclass

    def render(self) -> Text:
        self.renders += 1
        return self.draw()

    def draw(self) -> Text:
        raise NotImplementedError


class StatusLine(Bound):
    SOURCE = "status"
    DEFAULT_CSS = """
    StatusLine { dock: top; height: 1; background: $panel; color: $text; padding: 0 1; }
    StatusLine.alarm { background: $error; text-style: bold; }
    """
    view: reactive[StatusView] = reactive(StatusView)

    def watch_view(self, view: StatusView) -> None:
        self.set_class(view.alarm, "alarm")

    def draw(self) -> Text:
        return Text(self.view.text(), no_wrap=True, overflow="ellipsis")


class RobotPanel(Bound):
    SOURCE = "robot"
    view: reactive[RobotView] = reactive(RobotView)

    def draw(self) -> Text:
        r = self.view
        t = Text()
        if r.link_down:
            t.append(LINK_DOWN, "bold red")
        elif r.starting:
            t.append("Starting: connecting to the robot…\n", "bold yellow")
        if r.too_small:
            t.append("Terminal too small: robot stopped.\n", "bold red")
        if r.warning:
            t.append(f"{r.warning}\n", "bold red")
        t.append("Command  ", "bold")
        t.append(f"v {r.v_cmd:+.2f} m/s  ω {r.w_cmd:+.2f} rad/s\n")
        t.append("Max      ", "bold")
        t.append(f"speed {r.speed:.2f}  turn {r.turn:.2f}\n")
        t.append("Pose     ", "bold")
        t.append(f"x {r.x:+.2f} y {r.y:+.2f} θ {r.theta:+.2f} rad\n")
        t.append("Odom     ", "bold")
        t.append(f"v {r.v_odom:+.2f}  ω {r.w_odom:+.2f}\n")
        t.append("Algo     ", "bold")
        t.append(f"{r.algorithm} ({r.state})\n")
        t.append("Mission  ", "bold")
        t.append(f"{r.mission} {r.done}/{r.total}\n")
        t.append("Goal     ", "bold")
        t.append("none (manual)\n" if r.goal is None else f"({r.goal[0]:+.2f}, {r.goal[1]:+.2f})\n")
        t.append("Errors   ", "bold")
        if r.e_d is None or r.e_th is None:
            t.append("—")
        else:
            t.append(f"e_d {r.e_d:.2f} m  e_θ {r.e_th:+.2f} rad")
        return t


def heading_arrow(theta: float) -> str:
    return ARROWS[round(theta / (math.pi / 4)) % 8]


@dataclass(frozen=True, slots=True)
class MapFrame:
    """Where the world sits on a character map: equal aspect, a cell twice as tall as it is wide."""

    width: int
    height: int
    cx: float
    cy: float
    m_per_col: float

    @classmethod
    def around(cls, width: int, height: int, pts: Sequence[tuple[float, float]]) -> MapFrame:
        pts = list(pts) or [(0.0, 0.0)]
        xs = [p[0] for p in pts]
        ys = [p[1] for p in pts]
        span_x = max(max(xs) - min(xs), 1.0) * 1.15
        span_y = max(max(ys) - min(ys), 1.0) * 1.15
        return cls(
            width, height, (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2,
            max(span_x / width, span_y / (2 * height)),
        )  # fmt: skip

    def cell(self, x: float, y: float) -> tuple[int, int] | None:
        """(row, column) of a world point, None when off the map."""
        c = round((x - self.cx) / self.m_per_col + self.width / 2 - 0.5)
        r = round(self.height / 2 - 0.5 - (y - self.cy) / (2 * self.m_per_col))
        if 0 <= c < self.width and 0 <= r < self.height:
            return r, c
        return None

    def world(self, row: int, col: int) -> tuple[float, float]:
        """The world point at the centre of a cell (what a click there means)."""
        return (
            self.cx + (col + 0.5 - self.width / 2) * self.m_per_col,
            self.cy + (self.height / 2 - 0.5 - row) * 2 * self.m_per_col,
        )


def render_map(
    width: int,
    height: int,
    trail: Sequence[tuple[float, float]],
    pose: tuple[float, float, float] | None,
    goal: tuple[float, float] | None,
    waypoints: Sequence[tuple[float, float]] = (),
) -> tuple[Text, MapFrame]:
    """A character map of the trajectory with equal aspect, and the frame it was drawn in."""
    width, height = max(width, 4), max(height, 3)
    pts = list(trail) + list(waypoints)
    if pose is not None:
        pts.append((pose[0], pose[1]))
    if goal is not None:
        pts.append(goal)
    frame = MapFrame.around(width, height, pts)
    grid = [[" "] * width for _ in range(height)]
    styles: dict[tuple[int, int], str] = {}

    def put(x: float, y: float, ch: str, style: str) -> None:
        rc = frame.cell(x, y)
        if rc:
            grid[rc[0]][rc[1]] = ch
            styles[rc] = style

    for x, y in trail:
        put(x, y, "·", "cyan")
    for x, y in waypoints:
        put(x, y, "o", "yellow")
    if goal is not None:
        put(goal[0], goal[1], "G", "bold magenta")
    if pose is not None:
        put(pose[0], pose[1], heading_arrow(pose[2]), "bold green")
    text = Text(no_wrap=True, overflow="crop")
    for r, row in enumerate(grid):
        # one span per run of equally styled cells, not one per character
        start = 0
        for c in range(1, width + 1):
            if c == width or styles.get((r, c), "") != styles.get((r, start), ""):
                text.append("".join(row[start:c]), styles.get((r, start), ""))
                start = c
        if r < height - 1:
            text.append("\n")
    return text, frame


class GridMap(Bound):
    """A character map. Its grid is cheap to compute and costly to paint, so a new snapshot is painted
    only when the grid it gives (at the widget's current size) differs from the one shown."""

    DEFAULT_CSS = """
    GridMap { border: round $primary; height: 1fr; width: 1fr; }
    """
    _shown: Text | None = None
    _shown_size: Size | None = None

    def grid(self, width: int, height: int) -> Text:
        raise NotImplementedError

    def watch_view(self) -> None:
        size = self.content_size
        if size.width <= 0 or size.height <= 0:
            return  # not laid out yet: the first paint computes it
        text = self.grid(size.width, size.height)
        if (text, size) != (self._shown, self._shown_size):
            self._shown, self._shown_size = text, size
            self.refresh()

    def draw(self) -> Text:
        size = self.content_size
        if self._shown is None or size != self._shown_size:
            self._shown, self._shown_size = self.grid(size.width, size.height), size
        return self._shown


class TrajectoryMap(GridMap):
    """The live trail, pose, goal and waypoints (the control screen)."""

    SOURCE = "trajectory"
    view: reactive[MapView] = reactive(MapView, repaint=False)

    frame: MapFrame | None = None

    def grid(self, width: int, height: int) -> Text:
        v = self.view
        text, self.frame = render_map(width, height, v.trail, v.pose, v.goal, v.waypoints)
        return text

    def on_click(self, event: events.Click) -> None:
        """A click on the map sets a go-to-goal target there."""
        offset = event.get_content_offset(self)
        if offset is None or self.frame is None:
            return
        x, y = self.frame.world(offset.y, offset.x)
        self.post_message(GoalPicked(round(x, 2), round(y, 2)))


class StatsCards(Bound):
    SOURCE = "analytics"
    view: reactive[AnalyticsView] = reactive(AnalyticsView)

    def draw(self) -> Text:
        stats = self.view.stats
        t = Text()
        for i, name in enumerate(STATS_FIELDS):
            t.append(f"{STAT_LABELS[name].short:>10} ", "bold")
            t.append(f"{format_stat(name, getattr(stats, name)):<16}")
            if i % 3 == 2 and i < len(STATS_FIELDS) - 1:
                t.append("\n")
        return t


def fmt_ms(value: object) -> str:
    if value is None:
        return "N/A"
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return f"{value:.3f} ms"
    return "?"


def fmt_signed(value: float | None) -> str:
    return "N/A" if value is None else f"{value:+.3f} ms"


CARDS = (("count", "count"), ("mean_ms", "mean"), ("min_ms", "min"), ("max_ms", "max"), ("p95_ms", "p95"),
         ("stddev_ms", "stddev"))  # fmt: skip


class TrackerLine(Bound):
    SOURCE = "latency"
    view: reactive[LatencySnapshot] = reactive(LatencySnapshot)

    def draw(self) -> Text:
        v = self.view
        state = Text()
        if v.simulated:
            state.append("Client-side simulation: no network path, latency N/A", "bold")
        elif v.reachable is None:
            state.append("Polling the tracker…", "bold")
        elif not v.reachable:
            at = f" at {v.url}" if v.url else ""
            state.append(f"TRACKER UNREACHABLE{at}: {v.error} — retrying every 0.5 s", "bold red")
        else:
            state.append("tracker reachable", "bold green")
            kept = v.stat("count")
            state.append(f" · deploy mode {v.deploy}" + ("" if kept is None else f" · tracker keeps {kept}"))
            if v.stale:  # the robot ignores these: the operator must know why it does not move
                limit = "" if v.max_command_age_ms is None else f" > {v.max_command_age_ms:g} ms"
                state.append(f" · {v.stale} STALE{limit}, not forwarded", "bold red")
            if v.rejected:
                state.append(f" · {v.rejected} rejected", "bold yellow")
        return state


class TrackerCards(Bound):
    """One-way latency over the console's window of the tracker's records: the same records, and so the
    same p95, as the plot and the histogram beside it."""

    SOURCE = "latency"
    view: reactive[LatencySnapshot] = reactive(LatencySnapshot)

    def draw(self) -> Text:
        s = self.view.summary
        cards = Text()
        span = "" if s is None else f", {self.view.span_s:.0f} s"
        cards.append(f"one-way, last {0 if s is None else s.count} commands{span}\n", "bold")
        for i, (key, label) in enumerate(CARDS):
            value = None if s is None else getattr(s, key.removesuffix("_ms"))
            text = "N/A" if value is None else (str(value) if key == "count" else fmt_ms(value))
            cards.append(f"{label:>7} ", "bold")
            cards.append(f"{text:<14}")
            if i == 2:
                cards.append("\n")
        return cards


class ClientLine(Bound):
    """This console's own view: round trip, offset (NTP method), corrected one-way, loss."""

    SOURCE = "latency"
    view: reactive[LatencySnapshot] = reactive(LatencySnapshot)

    def watch_view(self, view: LatencySnapshot) -> None:
        self.display = not view.simulated

    def draw(self) -> Text:
        v = self.view
        out = Text()
        if v.simulated:
            return out
        s = v.client()
        out.append("this console", "bold")
        if v.link_down:
            out.append(
                f" · ROSBRIDGE LINK {v.link_state}: no commands, no round trips"
                f" · sent {s['sent']} · lost {s['lost']}",
                "bold red",
            )
            return out
        if not s["n"]:
            out.append(f" · no round trips yet · sent {s['sent']} · lost {s['lost']}")
            return out
        out.append(f" · rtt p50 {fmt_ms(s['rtt_p50_ms'])} p95 {fmt_ms(s['rtt_p95_ms'])}")
        out.append(
            f" · one-way corrected p50 {fmt_ms(s['corrected_p50_ms'])} (raw {fmt_ms(s['raw_p50_ms'])})\n"
        )
        off, unc = s["offset_ms"], s["offset_uncertainty_ms"]
        out.append(f"clock offset {fmt_signed(off)} ± {fmt_ms(unc)}")
        out.append(f" · negative {s['negative']} · lost {s['lost_in_window']} in 10 s ({s['lost']} total)")
        if s.get("late"):
            out.append(f" · late {s['late']} (queued, not lost)")
        warn = v.offset_warn_ms
        if off is not None and unc is not None and OffsetEstimate(off, unc, 2 * unc, 1).significant(warn):
            out.append(
                f"\nCLOCK OFFSET {off:+.1f} ms exceeds {warn:g} ms: raw one-way figures include it",
                "bold red",
            )
        return out
