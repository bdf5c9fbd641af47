"""Plot axes: ticks at round values, every gap the same number of cells, as textual-plot maps them."""

import itertools
import random

from textual.geometry import Region
from textual_plot.plot_widget import map_coordinate_to_pixel

from arbiter_tui.analytics import axes


def gaps(cells: list[int]) -> set[int]:
    return {abs(b - a) for a, b in itertools.pairwise(cells)}


def test_aligned_ticks_are_round_and_evenly_spaced_in_cells():
    rng = random.Random(1)
    for _ in range(2000):
        lo = rng.uniform(-50, 50)
        hi = lo + 10 ** rng.uniform(-2, 3)
        cells = rng.randint(3, 80)
        ax = axes.aligned(lo, hi, cells, rng.choice([2, 3, 8]))
        assert ax.lo <= lo and ax.hi >= hi
        region = Region(1, 1, cells, cells)
        rows = [map_coordinate_to_pixel(0, t, 0, 1, ax.lo, ax.hi, region)[1] for t in ax.ticks]
        cols = [map_coordinate_to_pixel(t, 0, ax.lo, ax.hi, 0, 1, region)[0] for t in ax.ticks]
        if len(ax.ticks) > 1:
            assert gaps(rows) == gaps(cols) == {ax.cells_per_tick}, (lo, hi, cells, ax)
            step = ax.ticks[1] - ax.ticks[0]
            assert f"{step:.10g}".lstrip("0.").rstrip("0")[:1] in ("1", "2", "5")


def test_equal_aspect_axes_keep_one_metre_as_long_across_as_up():
    rng = random.Random(2)
    for _ in range(1000):
        x0, y0 = rng.uniform(-5, 5), rng.uniform(-5, 5)
        x1, y1 = x0 + rng.uniform(0.1, 20), y0 + rng.uniform(0.1, 20)
        cols, rows = rng.randint(20, 120), rng.randint(6, 40)
        ax, ay = axes.equal_aspect_axes(x0, x1, y0, y1, cols, rows, 2.0, 8)
        assert ax.lo <= x0 and ax.hi >= x1 and ay.lo <= y0 and ay.hi >= y1
        assert abs(((ay.hi - ay.lo) / rows) / ((ax.hi - ax.lo) / cols) - 2.0) < 1e-9
        region = Region(1, 1, cols, rows)
        cols_at = [map_coordinate_to_pixel(t, 0, ax.lo, ax.hi, 0, 1, region)[0] for t in ax.ticks]
        rows_at = [map_coordinate_to_pixel(0, t, 0, 1, ay.lo, ay.hi, region)[1] for t in ay.ticks]
        assert len(gaps(cols_at)) <= 1 and len(gaps(rows_at)) <= 1


def test_a_count_axis_in_decades_and_gaps_in_time():
    ax = axes.decades(3.75, 10)
    assert ax.ticks == (1.0, 2.0, 3.0, 4.0) and ax.lo < 0 and ax.hi >= 3.75
    assert axes.gaps([0.0, 0.1, 0.2, 30.0, 30.1], 1.0) == [slice(0, 3), slice(3, 5)]
    assert axes.gaps([], 1.0) == []
