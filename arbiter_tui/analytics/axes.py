"""Plot axes whose ticks sit at round values *and* an equal number of character cells apart (pure).

A terminal plot maps values to whole cells, so ticks at 0, 100, 200... land 3, 3, 2, 3 rows apart unless
the axis limits are chosen for it; the eye reads uneven gaps as uneven steps. Here the limits are chosen
so that one tick step is exactly ``d`` cells, and each tick sits a quarter of a cell inside its cell, away
from the edges where rounding (and textual-plot's special case for a tick at the very limit) would move it.

textual-plot maps a value ``v`` to column ``floor(x0 + (v - lo) / per_cell)`` and to row
``ceil(bottom - 1 - (v - lo) / per_cell)``; both give exactly ``k * d`` cells for the k-th tick when
``(tick_k - lo) / per_cell = k * d + 1/4``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

STEPS = (1.0, 2.0, 5.0)
INSET = 0.25  # of a cell: where the first tick sits from the axis limit


@dataclass(frozen=True, slots=True)
class Axis:
    lo: float
    hi: float
    ticks: tuple[float, ...]
    cells_per_tick: int


def _nice_steps(smallest: float) -> list[float]:
    """Round steps (1, 2, 5 times a power of ten) from about ``smallest`` upwards."""
    e = math.floor(math.log10(smallest)) if smallest > 0 else 0
    return [m * 10.0**k for k in range(e - 1, e + 4) for m in STEPS if m * 10.0**k >= smallest * 0.999]


def _ticks(lo: float, hi: float, step: float) -> tuple[float, ...]:
    first = math.ceil(lo / step) * step
    n = math.floor((hi - first) / step + 1e-9) + 1
    return tuple(round(first + k * step, 10) for k in range(max(0, n)))


def aligned(lo: float, hi: float, cells: int, min_gap: int) -> Axis:
    """An axis over at least [lo, hi] on ``cells`` cells, ticks at round values ``min_gap`` or more cells
    apart, every gap the same number of cells."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        lo, hi = 0.0, 1.0
    if hi <= lo:
        lo, hi = lo - 0.5, lo + 0.5
    cells = max(cells, 2)
    min_gap = max(1, min(min_gap, cells - 1))
    span = hi - lo
    for step in _nice_steps(span * min_gap / cells):
        first = math.floor(lo / step) * step
        need = hi - first
        d = math.floor((cells - 2 * INSET) * step / need) if need > 0 else cells
        if d >= min_gap:
            per_cell = step / d
            a = first - INSET * per_cell
            b = a + cells * per_cell
            return Axis(a, b, _ticks(a, b, step), d)
    # too few cells for any tick: the plain range
    return Axis(lo, hi, (), cells)


def equal_aspect_axes(
    x0: float, x1: float, y0: float, y1: float, cols: int, rows: int, cell_aspect: float, min_gap_x: int
) -> tuple[Axis, Axis]:
    """Axes showing [x0, x1] x [y0, y1] with one metre as long across as up (a cell ``cell_aspect`` times
    taller than wide), the same round tick step on both, ticks an equal number of cells apart."""
    cols, rows = max(cols, 2), max(rows, 2)
    span_x, span_y = max(x1 - x0, 1e-6), max(y1 - y0, 1e-6)
    # metres per column, with the cells the alignment below may cost (a cell and the inset)
    m_min = max(span_x / max(cols - 1.5, 0.5), span_y / (cell_aspect * max(rows - 1.5, 0.5)))
    best: tuple[float, float, int] | None = None  # (metres per column, step, columns per tick)
    for step in _nice_steps(m_min * min_gap_x):  # the smallest round step that fits: the most ticks
        d = math.floor(step / m_min)
        d -= d % round(cell_aspect) if cell_aspect >= 1 else 0  # rows per tick = d / aspect, whole
        if d >= min_gap_x:
            best = (step / d, step, d)
            break
    if best is None:
        return aligned(x0, x1, cols, min_gap_x), aligned(y0, y1, rows, 2)
    m, step, d = best
    out = []
    for lo, hi, cells, per_cell in ((x0, x1, cols, m), (y0, y1, rows, m * cell_aspect)):
        # the axis starts a quarter cell before a whole cell: the lowest and highest such starts that
        # still show [lo, hi], and the one between them (the data centred, to a cell)
        j_max = math.floor(lo / per_cell + INSET)
        j_min = math.ceil((hi - cells * per_cell) / per_cell + INSET)
        j = max(j_min, min(j_max, round((j_min + j_max) / 2)))
        a = (j - INSET) * per_cell
        b = a + cells * per_cell
        out.append(Axis(a, b, _ticks(a, b, step), round(step / per_cell)))
    return out[0], out[1]


def cell(value: float, axis: Axis, cells: int) -> int:
    """The cell (0 at ``axis.lo``) a value falls in on an axis of ``cells`` cells (outside: < 0, >= cells)."""
    return math.floor((value - axis.lo) / (axis.hi - axis.lo) * cells)


def around(
    xs: list[float], ys: list[float], cols: int, rows: int, cell_aspect: float, min_gap_x: int
) -> tuple[Axis, Axis]:
    """Equal-aspect axes around points (a tenth of their span, at least 0.1 m, added on every side): a
    map of a path in metres."""
    if not xs:
        xs, ys = [0.0], [0.0]
    pad_x, pad_y = max(max(xs) - min(xs), 1.0) * 0.1, max(max(ys) - min(ys), 1.0) * 0.1
    return equal_aspect_axes(
        min(xs) - pad_x, max(xs) + pad_x, min(ys) - pad_y, max(ys) + pad_y, cols, rows, cell_aspect, min_gap_x
    )


def decades(top: float, cells: int) -> Axis:
    """A log10 count axis drawn as ``log10(count) + 1`` (a count of 1 is one decade tall, not nothing):
    ticks at whole decades (labelled 1, 10, 100... by the caller), an equal number of cells apart."""
    n = max(1, math.ceil(top - 1e-9))
    cells = max(cells, 2)
    step = 1
    while math.floor((cells - 2 * INSET) * step / n) < 1:
        step += 1
    d = math.floor((cells - 2 * INSET) * step / n)
    per_cell = step / d
    a = -INSET * per_cell
    return Axis(a, a + cells * per_cell, tuple(float(k) for k in range(step, n + 1, step)), d)


def gaps(t: list[float] | tuple[float, ...], min_gap: float) -> list[slice]:
    """Slices of ``t`` (ascending) between which more than ``min_gap`` passed: a line is not drawn
    across a time with no samples."""
    out, start = [], 0
    for i in range(1, len(t)):
        if t[i] - t[i - 1] > min_gap:
            out.append(slice(start, i))
            start = i
    if t:
        out.append(slice(start, len(t)))
    return out
