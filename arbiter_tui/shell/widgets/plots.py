"""Plots drawn with ``textual-plot`` (axes, ticks, labels, legends, braille resolution), fed by snapshots.

Each plot is bound to its screen's frame, picks its typed part (``pick``) and redraws only when the
data it draws changed (``data_key``: the store's version, a poll, the robot's cell; a frozen value
with named fields). Series are distinguished by marker shape and named in a legend, never by colour
alone. The plots take no focus and no keys: the screens' keys stay the screens'.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np
from textual import events
from textual.reactive import reactive
from textual_hires_canvas.canvas import Canvas
from textual_plot import HiResMode, PlotWidget
from textual_plot.axis_formatter import AxisFormatter

from arbiter_core.controllers import MANUAL

from ...analytics import axes
from ...analytics.linkcurve import LinkCurve, LinkSweepView, format_ms
from ...analytics.styles import GOAL, ROBOT_ARROWS, WAYPOINT, style_of
from ...session.frames import Frame
from ...session.views import PLOT_PERIOD_S, AnalyticsView, LatencySnapshot, MapView, thin
from ..messages import GoalPicked
from ..perf.canvas_rows import changed_rows_only

V = TypeVar("V")  # the part of the frame a plot shows
K = TypeVar("K")  # what it draws of it: equal keys, equal drawings


def algorithm_style(name: str) -> tuple[str, str]:
    """The terminal marker and colour of controller ``name``: the same on every plot (styles.py)."""
    style = style_of(name)
    return style.marker, style.colour


CELL_ASPECT = 2.0  # a terminal cell is about twice as tall as it is wide
MIN_GAP_X = 8  # columns between x ticks: room for a label like "-12.5"
MIN_GAP_Y = 2  # rows between y ticks
LINE_GAP_S = 1.0  # latency and error over time: no line across a second with nothing recorded


SHORT_NAMES = {MANUAL: "man", "waypoint": "wpt"}


def short_name(name: str) -> str:
    """go_to_goal -> gtg, pure_pursuit -> pp, manual -> man: for a legend that would not fit."""
    parts = name.split("_")
    return "".join(p[0] for p in parts) if len(parts) > 1 else SHORT_NAMES.get(name, name)


def legend_text(items: Sequence[tuple[str, str]], width: int) -> str:
    """``marker name`` pairs in one line of at most ``width`` cells: full names, else short ones, else
    as many whole entries as fit (the first ones) and an ellipsis."""
    for name_of in (str, short_name):
        text = " ".join(f"{m} {name_of(n)}" for m, n in items)
        if len(text) <= width:
            return text
    shown: list[str] = []
    for m, n in items:
        entry = f"{m} {short_name(n)}"
        if len(" ".join([*shown, entry, "…"])) > width:
            break
        shown.append(entry)
    return " ".join([*shown, "…"]) if shown else ""


class DecadeFormatter(AxisFormatter):
    """Labels for a log10 count axis drawn as log10(count) + 1: 1 -> "1", 2 -> "10", 3 -> "100"."""

    def get_ticks(self, min_: float, max_: float, max_ticks: int = 8) -> list[float]:
        return [float(k) for k in range(1, int(max_) + 1)]

    def get_labels_for_ticks(self, ticks: Sequence[float]) -> list[str]:
        return [f"{10 ** (round(t) - 1):g}" for t in ticks]


class PlotBudget:
    """The plot redraws one frame allows. A plot redraw is the dearest paint, and several in one frame
    made it longer than a control period under a Pi-class quota; the others draw in the frames after
    (bench/pi.py). Each screen has one, handed down to its plots (``data_bind``); the app renews it with
    every frame it hands on; the plots spend it, and say when one of them waits for the next frame."""

    def __init__(self) -> None:
        self.left: int | None = None  # redraws left in this frame (None: any number)
        self.waiting = False  # a plot put off its redraw: the next frame is handed on even if unchanged

    def renew(self, draws: int | None) -> None:
        self.left, self.waiting = draws, False

    def take(self) -> bool:
        """One of this frame's redraws, if one is left."""
        if self.left is None:
            return True
        if self.left <= 0:
            return False
        self.left -= 1
        return True


class Plot(PlotWidget, Generic[V, K], can_focus=False):
    """A PlotWidget that shows one part of the frame (``pick``), redrawn only when what it draws changed
    (``data_key``, a value that compares equal exactly when the drawing would be the same). Bind it with
    ``.data_bind(BaseScreen.frame, BaseScreen.plot_budget)``."""

    DEFAULT_CSS = """
    Plot { border: round $primary; height: 1fr; width: 1fr; }
    """
    # every frame (equal or not): a change that waits for its follow period is drawn at the first frame
    # after it, in the same paint as the widgets that changed with that frame
    frame: reactive[Frame] = reactive(Frame, repaint=False, always_update=True)
    plot_budget: reactive[PlotBudget] = reactive(PlotBudget, repaint=False)  # the screen's, handed down
    draws = 0  # tests: how often the data was redrawn

    def __init__(self, title: str, **kwargs: Any) -> None:
        super().__init__(allow_pan_and_zoom=False, **kwargs)
        self.border_title = title
        self._key: K | None = None
        self._drawn_at = float("-inf")  # monotonic s

    def on_mount(self) -> None:
        # axis names and units are in the border title: the margins hold just the tick labels
        self.margin_top = 0
        self.margin_bottom = 1
        self.margin_left = 7

    def pick(self, frame: Frame) -> V:
        raise NotImplementedError

    def watch_frame(self, frame: Frame) -> None:
        if self.is_mounted:
            self._receive(self.pick(frame), budgeted=True)

    def _receive(self, view: V, budgeted: bool = False) -> None:
        key = self.data_key(view)
        if key == self._key:
            return  # nothing this plot draws changed
        wait = self.follow_period(self._key, key) - (time.monotonic() - self._drawn_at)
        if wait > 0 or (budgeted and not self.plot_budget.take()):
            # drawn at the first frame after its period, or after the plot that drew in this one, with
            # what is newest then
            self.plot_budget.waiting = True
            return
        self._key = key
        self._drawn_at = time.monotonic()
        self.draws += 1
        with changed_rows_only(self.query(Canvas)):  # only the rows that changed are painted again
            self.clear()
            self.draw(view)
            if self.size.area:
                # Draw onto the canvases now rather than in the next paint: textual-plot does it in
                # render(), during a frame, and the canvases it dirties then take a frame of their own.
                self.render()

    def follow_period(self, old: K | None, new: K) -> float:
        """How long after the last draw a change from ``old`` to ``new`` may wait (0: draw at once)."""
        return 0.0

    def on_resize(self) -> None:
        self._key = None  # limits that keep an aspect depend on the size
        self._receive(self.pick(self.frame))

    def canvas_size(self) -> tuple[int, int]:
        """Columns and rows of the data area, from this widget's own size (known when it is resized,
        before the library has laid out its inner canvas)."""
        size = self.content_size
        return (
            max(1, size.width - self.margin_left),
            max(1, size.height - self.margin_top - self.margin_bottom),
        )

    def scale_size(self) -> tuple[int, int]:
        """Columns and rows inside the axis lines: what values are mapped onto."""
        cols, rows = self.canvas_size()
        return max(2, cols - 2), max(2, rows - 2)

    def set_axes(self, x: axes.Axis | None, y: axes.Axis) -> None:
        """Limits and ticks from ``axes`` (ticks at round values, evenly spaced in cells)."""
        if x is not None:
            self.set_xlimits(x.lo, x.hi)
            self.set_xticks(list(x.ticks))
        self.set_ylimits(y.lo, y.hi)
        self.set_yticks(list(y.ticks))

    def trace(self, t: np.ndarray, y: np.ndarray, min_gap: float, budget: int | None = None) -> None:
        """``y`` over ``t`` as a cyan braille line with no line across a gap longer than ``min_gap`` (a
        lone sample between two gaps: a dot); ``budget``: at most about that many points in all (thinned
        evenly in each part, none when None)."""
        for part in axes.gaps(t.tolist(), min_gap):
            seg_t, seg_y = t[part], y[part]
            if budget is not None:
                pick = thin(seg_t.size, max(2, budget * seg_t.size // t.size))
                seg_t, seg_y = seg_t[pick], seg_y[pick]
            if seg_t.size > 1:
                self.plot(seg_t, seg_y, line_style="cyan", hires_mode=HiResMode.BRAILLE)
            else:  # one sample between two gaps: a dot, not a line to its neighbours
                self.scatter(seg_t, seg_y, marker="•", marker_style="cyan")

    def data_key(self, view: V) -> K:
        raise NotImplementedError

    def draw(self, view: V) -> None:
        raise NotImplementedError


class ErrorPlot(Plot[AnalyticsView, int]):
    """Distance error over time (the newest samples)."""

    def pick(self, frame: Frame) -> AnalyticsView:
        return frame.analytics

    def data_key(self, view: AnalyticsView) -> int:
        return view.plot_version

    def draw(self, view: AnalyticsView) -> None:
        cols, rows = self.scale_size()
        if view.errors:
            t, e = np.asarray(view.error_t, dtype=np.float64), np.asarray(view.errors, dtype=np.float64)
            # no line across a gap in the record (the link down, odometry stale, nothing recorded): a gap
            # is more than LINE_GAP_S, or three of the plotted samples' usual steps where they are sparser
            step = float(np.median(np.diff(t))) if t.size > 2 else 0.0
            budget = 2 * self.canvas_size()[0]  # braille: two dots a cell across; more draw the same line
            self.trace(t, e, max(LINE_GAP_S, 3.0 * step), budget)
            x = axes.aligned(view.error_t[0], max(view.error_t[-1], view.error_t[0] + 1.0), cols, MIN_GAP_X)
            self.set_axes(x, axes.aligned(0.0, max(max(view.errors) * 1.05, 0.1), rows, MIN_GAP_Y))
        else:
            self.set_axes(axes.aligned(0.0, 10.0, cols, MIN_GAP_X), axes.aligned(0.0, 1.0, rows, MIN_GAP_Y))


@dataclass(frozen=True)
class Mission:
    """What a map shows of the mission: a change draws at once."""

    goal: tuple[float, float] | None
    waypoints: tuple[tuple[float, float], ...]
    stale: bool = False


@dataclass(frozen=True)
class TrajectoryKey:
    plot_version: int
    mission: Mission


@dataclass(frozen=True)
class MapKey:
    x_axis: axes.Axis
    y_axis: axes.Axis
    robot: tuple[int, int, str] | None  # the robot's cell and its heading arrow
    mission: Mission


class MapPlot(Plot[V, K]):
    """A path in metres at equal aspect: the axes are the scale. Shared by the analytics trajectory and
    the control screen's live map, so both are drawn (and read) the same way."""

    def map_axes(
        self,
        xs: list[float],
        ys: list[float],
        waypoints: tuple[tuple[float, float], ...],
        goal: tuple[float, float] | None,
    ) -> tuple[axes.Axis, axes.Axis]:
        xs, ys = list(xs), list(ys)
        for wx, wy in waypoints + ((goal,) if goal is not None else ()):
            xs.append(wx)
            ys.append(wy)
        cols, rows = self.scale_size()
        return axes.around(xs, ys, cols, rows, CELL_ASPECT, MIN_GAP_X)

    def draw_mission(
        self, waypoints: tuple[tuple[float, float], ...], goal: tuple[float, float] | None
    ) -> list[tuple[str, str]]:
        """The waypoints ``o`` and the goal ``G``; their legend entries."""
        legend = []
        if waypoints:
            wx, wy = zip(*waypoints, strict=True)
            self.scatter(wx, wy, marker=WAYPOINT.marker, marker_style=WAYPOINT.colour)
            legend.append((WAYPOINT.marker, "waypoint"))
        if goal is not None:
            self.scatter([goal[0]], [goal[1]], marker=GOAL.marker, marker_style=GOAL.colour)
            legend.append((GOAL.marker, "goal"))
        return legend

    def one_per_cell(
        self, x: np.ndarray, y: np.ndarray, x_axis: axes.Axis, y_axis: axes.Axis
    ) -> tuple[np.ndarray, np.ndarray]:
        """The first point in each character cell: a marker drawn twice in a cell looks the same, and the
        plot library pays for every point."""
        if x.size == 0:
            return x, y
        cols, rows = self.scale_size()
        c = np.floor((x - x_axis.lo) / (x_axis.hi - x_axis.lo) * cols).astype(np.int64)
        r = np.floor((y - y_axis.lo) / (y_axis.hi - y_axis.lo) * rows).astype(np.int64)
        _, first = np.unique(r * (cols + 1) + c, return_index=True)
        first.sort()
        return x[first], y[first]


class TrajectoryPlot(MapPlot[AnalyticsView, TrajectoryKey]):
    """The collected path, one marker per algorithm (legend), the mission's waypoints ``o`` and goal ``G``,
    at equal aspect: the axes in metres are the scale."""

    def pick(self, frame: Frame) -> AnalyticsView:
        return frame.analytics

    def data_key(self, view: AnalyticsView) -> TrajectoryKey:
        return TrajectoryKey(view.plot_version, Mission(view.goal, view.waypoints))

    def draw(self, view: AnalyticsView) -> None:
        tracks = [(t, np.asarray(t.x), np.asarray(t.y)) for t in view.tracks]
        xs = [float(v) for _t, x, _y in tracks for v in (x.min(), x.max())]
        ys = [float(v) for _t, _x, y in tracks for v in (y.min(), y.max())]
        x_axis, y_axis = self.map_axes(xs, ys, view.waypoints, view.goal)
        self.set_axes(x_axis, y_axis)
        legend: list[tuple[str, str]] = []
        for track, x, y in tracks:
            marker, colour = algorithm_style(track.algorithm)
            self.scatter(*self.one_per_cell(x, y, x_axis, y_axis), marker=marker, marker_style=colour)
            legend.append((marker, track.algorithm))
        legend += self.draw_mission(view.waypoints, view.goal)
        # the legend is text in the bottom border: it never hides the path
        self.border_subtitle = legend_text(legend, self.size.width - 6)


class LiveMap(MapPlot[MapView, MapKey]):
    """The control screen's map: the robot (an arrow along its heading), its trail, the origin ``+``, and
    the waypoints and goal where ``g`` takes it, drawn as the analytics trajectory is. Redrawn only when
    what it shows moves by a cell (the robot, the axes) or the mission changes, not at every pose. A click
    sets a go-to-goal target there."""

    view: MapView | None = None

    def pick(self, frame: Frame) -> MapView:
        return frame.map

    def data_key(self, view: MapView) -> MapKey:
        x_axis, y_axis = self._axes(view)
        cols, rows = self.scale_size()
        cell = None
        if view.pose is not None:
            x, y, theta = view.pose
            cell = (axes.cell(x, x_axis, cols), axes.cell(y, y_axis, rows), heading_arrow(theta))
        return MapKey(x_axis, y_axis, cell, Mission(view.goal, view.waypoints, view.stale))

    def follow_period(self, old: MapKey | None, new: MapKey) -> float:
        """The robot moving (by a cell, or out of the axes, which then grow) is drawn at most every
        ``FOLLOW_S``: a plot repaint was most of the control screen's CPU under a Pi-class quota
        (bench/pi.py), and a robot driving out of the map changed the axes at almost every tick. A new
        mission or goal, or a pose turning stale, is drawn at once. The panel beside it shows the pose at
        the full UI rate."""
        return FOLLOW_S if old is not None and old.mission == new.mission else 0.0

    def _axes(self, view: MapView) -> tuple[axes.Axis, axes.Axis]:
        xs, ys = [0.0], [0.0]  # the origin is always on the map
        if view.bounds is not None:
            xs += [view.bounds[0], view.bounds[1]]
            ys += [view.bounds[2], view.bounds[3]]
        if view.pose is not None:
            xs.append(view.pose[0])
            ys.append(view.pose[1])
        return self.map_axes(xs, ys, view.waypoints, view.goal)

    def draw(self, view: MapView) -> None:
        self.view = view
        x_axis, y_axis = self._axes(view)
        self.set_axes(x_axis, y_axis)
        legend = [("+", "origin")]
        self.scatter([0.0], [0.0], marker="+", marker_style="dim")
        if view.trail:
            trail = np.asarray(view.trail, dtype=np.float64)
            x, y = self.one_per_cell(trail[:, 0], trail[:, 1], x_axis, y_axis)
            self.scatter(x, y, marker="·", marker_style="cyan")
            legend.append(("·", "trail"))
        legend += self.draw_mission(view.waypoints, view.goal)
        if view.pose is not None:
            px, py, theta = view.pose
            arrow = heading_arrow(theta)
            self.scatter([px], [py], marker=arrow, marker_style="dim" if view.stale else "bold green")
            legend.insert(0, (arrow, "robot (stale)" if view.stale else "robot"))
        self.border_subtitle = legend_text(legend, self.size.width - 6)

    def on_click(self, event: events.Click) -> None:
        """A click inside the axes sets a go-to-goal target there (rounded to a centimetre)."""
        canvas = self.query_one("#plot")
        offset = event.get_content_offset(canvas)
        if offset is None or not self._scale_rectangle.contains(offset.x, offset.y):
            return
        x, y = self.get_coordinate_from_pixel(offset.x, offset.y)
        self.post_message(GoalPicked(round(x, 2), round(y, 2)))


FOLLOW_S = 0.5  # the live map follows the robot at most this often


def heading_arrow(theta: float) -> str:
    return ROBOT_ARROWS[round(theta / (math.pi / 4)) % 8]


@dataclass(frozen=True)
class WindowKey:
    polled: object  # the poll that brought the window
    simulated: bool


class _LatencyWindow(Plot[LatencySnapshot, WindowKey]):
    """A plot of the tracker's latency window: redrawn when a poll brought new records."""

    def pick(self, frame: Frame) -> LatencySnapshot:
        return frame.latency

    def data_key(self, view: LatencySnapshot) -> WindowKey:
        return WindowKey(view.polled, view.simulated)

    def follow_period(self, old: WindowKey | None, new: WindowKey) -> float:
        """While records stream in, the plots follow at most every ``PLOT_PERIOD_S``, as the analytics
        plots do (the cards and records above them: every poll); a plot repaint costs more than the
        numbers, and this screen must cost no more than the analytics screen (bench/pi.py)."""
        return PLOT_PERIOD_S if old is not None and old.simulated == new.simulated else 0.0


class LatencyPlot(_LatencyWindow):
    """The tracker's latencies over time (seconds before the newest), with their p95 as a line: the same
    window and p95 as the cards above. No line is drawn across a gap with no commands."""

    def draw(self, view: LatencySnapshot) -> None:
        if not view.window or view.summary is None:
            return
        t = np.asarray(view.window_t, dtype=np.float64)
        t = t - t[-1]
        lat = np.asarray(view.window, dtype=np.float64)
        p95 = view.summary.p95
        self.trace(t, lat, LINE_GAP_S)  # a lone command between two gaps: a dot
        cols, rows = self.scale_size()
        x = axes.aligned(float(t[0]) if t.size > 1 else -1.0, 0.0, cols, MIN_GAP_X)
        y = axes.aligned(0.0, max(float(lat.max()) * 1.05, 0.1), rows, MIN_GAP_Y)
        # the p95 as a row of "─" characters: told apart from the braille trace by shape, not colour
        self.scatter(np.linspace(x.lo, x.hi, cols), np.full(cols, p95), marker="─", marker_style="red")
        self.set_axes(x, y)
        self.border_subtitle = f"⠒ latency ─ p95 {p95:.2f} ms (last {view.summary.count})"


class LatencyHistogram(_LatencyWindow):
    """How the window's latencies are distributed: commands per bin on a log10 count axis (7 next to 563
    stays visible); an empty bin draws nothing."""

    BINS = 12

    def draw(self, view: LatencySnapshot) -> None:
        if not view.window:
            return
        lat = np.asarray(view.window, dtype=np.float64)
        lo, hi = float(lat.min()), float(lat.max())
        if math.isclose(lo, hi):
            lo, hi = lo - 0.5, hi + 0.5
        counts, edges = np.histogram(lat, bins=self.BINS, range=(lo, hi))
        centres = (edges[:-1] + edges[1:]) / 2
        full = counts > 0
        heights = np.log10(counts[full]) + 1.0
        self.bar(centres[full], heights, width=float(edges[1] - edges[0]) * 0.9, bar_style="cyan")
        cols, rows = self.scale_size()
        self.set_y_formatter(DecadeFormatter())
        self.set_axes(axes.aligned(lo, hi, cols, MIN_GAP_X), axes.decades(float(heights.max()), rows))
        self.border_subtitle = f"count (log) · {len(lat)} commands"


@dataclass(frozen=True)
class SweepKey:
    curve: LinkCurve | None
    p95_ms: float | None  # to the 0.1 ms the legend shows


class LinkPlot(Plot[LinkSweepView, SweepKey]):
    """Avg cross-track error against one-way latency, one line per controller (a sweep of the selected
    mission in simulated time), and the latency this console measures (its p95) as a vertical line."""

    def pick(self, frame: Frame) -> LinkSweepView:
        return frame.link_sweep

    def data_key(self, view: LinkSweepView) -> SweepKey:
        return SweepKey(view.curve, None if view.p95_ms is None else round(view.p95_ms, 1))

    def draw(self, view: LinkSweepView) -> None:
        cols, rows = self.scale_size()
        curve = view.curve
        if curve is None:
            self.set_axes(axes.aligned(0.0, 500.0, cols, MIN_GAP_X), axes.aligned(0.0, 0.1, rows, MIN_GAP_Y))
            return
        top = max(max(ys) for _name, ys in curve.errors) * 1.1 or 0.1
        x_hi = curve.latencies_ms[-1]
        # first: never cut; the same figure as the line of text below the plot
        legend = [] if view.p95_ms is None else [("│", f"p95 {format_ms(view.p95_ms)} ms")]
        for name, ys in curve.errors:
            marker, style = algorithm_style(name)
            self.plot(curve.latencies_ms, ys, line_style=style, hires_mode=HiResMode.BRAILLE)
            self.scatter(curve.latencies_ms, ys, marker=marker, marker_style=style)
            legend.append((marker, name))
        if view.p95_ms is not None:
            at = min(view.p95_ms, x_hi)
            self.plot([at, at], [0.0, top], line_style="bold red", hires_mode=HiResMode.BRAILLE)
        self.set_axes(axes.aligned(0.0, x_hi, cols, MIN_GAP_X), axes.aligned(0.0, top, rows, MIN_GAP_Y))
        self.border_subtitle = legend_text(legend, max(0, self.size.width - 4))
