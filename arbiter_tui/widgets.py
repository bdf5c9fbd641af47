"""Small widgets: the status line and the trajectory map (text rendering, equal aspect)."""

from __future__ import annotations

import math
from collections.abc import Sequence

from rich.text import Text
from textual.widgets import Static

from arbiter_core.kinematics import Pose

ARROWS = "→↗↑↖←↙↓↘"


def heading_arrow(theta: float) -> str:
    return ARROWS[round(theta / (math.pi / 4)) % 8]


def render_map(
    width: int,
    height: int,
    trail: Sequence[tuple[float, float]],
    pose: Pose | None,
    goal: tuple[float, float] | None,
    waypoints: Sequence[tuple[float, float]] = (),
) -> Text:
    """A character map of the trajectory with equal aspect (a cell is twice as tall as it is wide)."""
    width, height = max(width, 4), max(height, 3)
    pts = list(trail) + list(waypoints)
    if pose is not None:
        pts.append((pose.x, pose.y))
    if goal is not None:
        pts.append(goal)
    if not pts:
        pts = [(0.0, 0.0)]
    xs = [p[0] for p in pts]
    ys = [p[1] for p in pts]
    cx, cy = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2
    span_x = max(max(xs) - min(xs), 1.0) * 1.15
    span_y = max(max(ys) - min(ys), 1.0) * 1.15
    # metres per column / per row, with rows twice as tall as columns
    m_per_col = max(span_x / width, span_y / (2 * height))
    m_per_row = 2 * m_per_col
    grid = [[" "] * width for _ in range(height)]
    styles: dict[tuple[int, int], str] = {}

    def cell(x: float, y: float) -> tuple[int, int] | None:
        c = round((x - cx) / m_per_col + width / 2 - 0.5)
        r = round(height / 2 - 0.5 - (y - cy) / m_per_row)
        if 0 <= c < width and 0 <= r < height:
            return r, c
        return None

    for x, y in trail:
        rc = cell(x, y)
        if rc:
            grid[rc[0]][rc[1]] = "·"
            styles[rc] = "cyan"
    for x, y in waypoints:
        rc = cell(x, y)
        if rc:
            grid[rc[0]][rc[1]] = "o"
            styles[rc] = "yellow"
    if goal is not None:
        rc = cell(*goal)
        if rc:
            grid[rc[0]][rc[1]] = "G"
            styles[rc] = "bold magenta"
    if pose is not None:
        rc = cell(pose.x, pose.y)
        if rc:
            grid[rc[0]][rc[1]] = heading_arrow(pose.theta)
            styles[rc] = "bold green"
    text = Text(no_wrap=True, overflow="crop")
    for r, row in enumerate(grid):
        for c, ch in enumerate(row):
            text.append(ch, styles.get((r, c), ""))
        if r < height - 1:
            text.append("\n")
    return text


class MapView(Static):
    DEFAULT_CSS = """
    MapView { border: round $primary; height: 1fr; width: 1fr; }
    """

    def show(
        self,
        trail: Sequence[tuple[float, float]],
        pose: Pose | None,
        goal: tuple[float, float] | None,
        waypoints: Sequence[tuple[float, float]] = (),
    ) -> None:
        w, h = self.content_size.width, self.content_size.height
        if w <= 0 or h <= 0:
            return
        self.update(render_map(w, h, trail, pose, goal, waypoints))


class StatusLine(Static):
    DEFAULT_CSS = """
    StatusLine { dock: top; height: 1; background: $panel; color: $text; padding: 0 1; }
    StatusLine.alarm { background: $error; text-style: bold; }
    """
