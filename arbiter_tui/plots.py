"""Plots drawn with ``textual-plot`` (axes, ticks, labels, legends, braille resolution), fed by snapshots.

Each plot watches one app attribute and redraws only when the data it draws changed (the store's
version, a poll). Series are distinguished by marker shape and named in a legend, never by colour
alone. The plots take no focus and no keys: the screens' keys stay the screens'.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from textual_plot import HiResMode, PlotWidget

from arbiter_core import stats as S

from .views import AnalyticsView, LatencySnapshot, thin

# one marker shape (and colour) per algorithm; later names reuse them in order
ALGORITHM_STYLES: dict[str, tuple[str, str]] = {
    "manual": ("·", "bright_white"),
    "go_to_goal": ("+", "cyan"),
    "pure_pursuit": ("x", "magenta"),
}
EXTRA_STYLES = (("*", "green"), ("o", "yellow"), ("#", "red"))
CELL_ASPECT = 2.0  # a terminal cell is about twice as tall as it is wide


def algorithm_style(name: str, order: int) -> tuple[str, str]:
    return ALGORITHM_STYLES.get(name) or EXTRA_STYLES[order % len(EXTRA_STYLES)]


def equal_aspect(
    xs: list[float], ys: list[float], cols: int, rows: int, pad: float = 0.1
) -> tuple[float, float, float, float]:
    """Axis limits showing every point with one metre as long across as up (cells ``CELL_ASPECT`` tall)."""
    if not xs:
        xs, ys = [0.0], [0.0]
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    span_x = max(x1 - x0, 1.0) * (1 + 2 * pad)
    span_y = max(y1 - y0, 1.0) * (1 + 2 * pad)
    m_per_col = max(span_x / max(cols, 1), span_y / (CELL_ASPECT * max(rows, 1)))
    half_x = m_per_col * max(cols, 1) / 2
    half_y = m_per_col * CELL_ASPECT * max(rows, 1) / 2
    return cx - half_x, cx + half_x, cy - half_y, cy + half_y


def nice_ticks(lo: float, hi: float, most: int) -> list[float]:
    """Ticks at 1, 2 or 5 times a power of ten, at most ``most`` of them, between lo and hi."""
    span = hi - lo
    if not (math.isfinite(span) and span > 0) or most < 1:
        return []
    raw = span / most
    base = 10 ** math.floor(math.log10(raw))
    step = next(m * base for m in (1, 2, 5, 10) if m * base >= raw)
    first = math.ceil(lo / step) * step
    return [round(first + k * step, 10) for k in range(int((hi - first) / step + 1e-9) + 1)]


class Plot(PlotWidget, can_focus=False):
    """A PlotWidget that follows one snapshot attribute of the app (``SOURCE``)."""

    SOURCE: ClassVar[str] = ""
    DEFAULT_CSS = """
    Plot { border: round $primary; height: 1fr; width: 1fr; }
    """
    draws = 0  # tests: how often the data was redrawn

    def __init__(self, title: str, **kwargs: Any) -> None:
        super().__init__(allow_pan_and_zoom=False, **kwargs)
        self.border_title = title
        self._key: object = None

    def on_mount(self) -> None:
        # axis names and units are in the border title: the margins hold just the tick labels
        self.margin_top = 0
        self.margin_bottom = 1
        self.margin_left = 7
        self.watch(self.app, self.SOURCE, self._receive, init=True)

    def _receive(self, view: Any) -> None:
        key = self.data_key(view)
        if key == self._key:
            return  # nothing this plot draws changed
        self._key = key
        self.draws += 1
        self.clear()
        self.draw(view)

    def on_resize(self) -> None:
        self._key = None  # limits that keep an aspect depend on the size
        self._receive(getattr(self.app, self.SOURCE))

    def canvas_size(self) -> tuple[int, int]:
        """Columns and rows of the data area, from this widget's own size (known when it is resized,
        before the library has laid out its inner canvas)."""
        size = self.content_size
        return (
            max(1, size.width - self.margin_left),
            max(1, size.height - self.margin_top - self.margin_bottom),
        )

    def data_key(self, view: Any) -> object:
        raise NotImplementedError

    def draw(self, view: Any) -> None:
        raise NotImplementedError


class ErrorPlot(Plot):
    """Distance error over time (the newest samples)."""

    SOURCE = "analytics"

    def data_key(self, view: AnalyticsView) -> object:
        return view.plot_version

    def draw(self, view: AnalyticsView) -> None:
        if view.errors:
            # braille: two dots a cell across; more points than that draw the same line, slower
            pick = thin(len(view.errors), 2 * self.canvas_size()[0])
            self.plot(view.error_t[pick], view.errors[pick], line_style="cyan", hires_mode=HiResMode.BRAILLE)
            self.set_ylimits(0.0, max(max(view.errors) * 1.1, 0.1))
        else:
            self.set_ylimits(0.0, 1.0)


class TrajectoryPlot(Plot):
    """The collected path, one marker per algorithm (legend), the mission's waypoints ``o`` and goal ``G``,
    at equal aspect: the axes in metres are the scale."""

    SOURCE = "analytics"

    def data_key(self, view: AnalyticsView) -> object:
        return (view.plot_version, view.waypoints, view.goal)

    def draw(self, view: AnalyticsView) -> None:
        tracks = [(t, np.asarray(t.x), np.asarray(t.y)) for t in view.tracks]
        xs = [float(v) for _t, x, _y in tracks for v in (x.min(), x.max())]
        ys = [float(v) for _t, _x, y in tracks for v in (y.min(), y.max())]
        for wx, wy in view.waypoints + ((view.goal,) if view.goal is not None else ()):
            xs.append(wx)
            ys.append(wy)
        cols, rows = self.canvas_size()
        x0, x1, y0, y1 = equal_aspect(xs, ys, cols, rows)
        self.set_xlimits(x0, x1)
        self.set_ylimits(y0, y1)
        legend = []
        for i, (track, x, y) in enumerate(tracks):
            marker, colour = algorithm_style(track.algorithm, i)
            self.scatter(*self._one_per_cell(x, y), marker=marker, marker_style=colour)
            legend.append(f"{marker} {track.algorithm}")
        if view.waypoints:
            wx, wy = zip(*view.waypoints, strict=True)
            self.scatter(wx, wy, marker="o", marker_style="yellow")
            legend.append("o waypoint")
        if view.goal is not None:
            self.scatter([view.goal[0]], [view.goal[1]], marker="G", marker_style="bold red")
            legend.append("G goal")
        # the legend is text in the bottom border: it never hides the path
        self.border_subtitle = "  ".join(legend)
        self.set_xticks(nice_ticks(x0, x1, max(1, cols // 7)))
        self.set_yticks(nice_ticks(y0, y1, max(1, rows // 2)))

    def _one_per_cell(self, x: np.ndarray, y: np.ndarray) -> tuple[list[float], list[float]]:
        """The first point in each character cell (as the plot maps them): a marker drawn twice in a cell
        looks the same, and the plot library pays for every point. Before the first paint the plot's
        mapping is unknown: every point is kept."""
        if not self._scale_rectangle.area:
            return x.tolist(), y.tolist()
        cells: dict[tuple[int, int], tuple[float, float]] = {}
        for xi, yi in zip(x.tolist(), y.tolist(), strict=True):
            cells.setdefault(self.get_pixel_from_coordinate(xi, yi), (xi, yi))
        kept = list(cells.values())
        return [p[0] for p in kept], [p[1] for p in kept]


class _LatencyWindow(Plot):
    """A plot of the tracker's latency window: redrawn when a poll brought new records."""

    SOURCE = "latency"

    def data_key(self, view: LatencySnapshot) -> object:
        return (view.polled, view.simulated)


class LatencyPlot(_LatencyWindow):
    """The tracker's latencies over time (seconds before the newest), with their p95 as a line."""

    def draw(self, view: LatencySnapshot) -> None:
        if not view.window:
            return
        t = np.asarray(view.window_t, dtype=np.float64)
        t = t - t[-1]
        lat = np.asarray(view.window, dtype=np.float64)
        p95 = S.p95(lat)
        self.plot(t, lat, line_style="cyan", hires_mode=HiResMode.BRAILLE)
        left = float(t[0]) if t.size > 1 else -1.0
        # the p95 as a row of "─" characters: told apart from the braille trace by shape, not colour
        cols = max(2, self.canvas_size()[0])
        self.scatter(np.linspace(left, 0.0, cols), np.full(cols, p95), marker="─", marker_style="red")
        self.set_xlimits(left, 0.0)
        self.set_ylimits(0.0, max(float(lat.max()) * 1.15, 0.1))
        self.border_subtitle = f"⠒ latency  ─ p95 {p95:.2f} ms"


class LatencyHistogram(_LatencyWindow):
    """How the window's latencies are distributed (commands per bin)."""

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
        self.bar(centres, counts, width=float(edges[1] - edges[0]) * 0.9, bar_style="cyan")
        self.set_xlimits(lo, hi)
        self.set_ylimits(0.0, float(counts.max()) * 1.15)
        self.set_xticks(nice_ticks(lo, hi, max(1, self.canvas_size()[0] // 7)))
