"""``compare --plot FILE``: a sweep's avg cross-track error against latency as an SVG or PNG, for reports.

One panel per mission, one line per controller, its 95 % interval as a band when there are several
trials. matplotlib (the ``[report]`` extra) is imported only here, with the headless Agg backend.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from arbiter_core.cliargs import NOT_WRITABLE, can_create_in

from ..analytics.styles import style_of

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .compare import SweepCell


def series(cells: list[SweepCell]) -> dict[str, dict[str, list[tuple[float, float, float]]]]:
    """mission -> algorithm -> [(latency ms, mean avg e_xt, interval half-width)] in latency order."""
    out: dict[str, dict[str, list[tuple[float, float, float]]]] = {}
    for cell in sorted(cells, key=lambda c: c.link.latency_s):
        for s in cell.summaries:
            f = s.figures["xte_mean_m"]
            out.setdefault(s.mission, {}).setdefault(s.algorithm, []).append(
                (cell.link.latency_s * 1e3, f.mean, f.ci95)
            )
    return out


INSTALL = "pip install 'arbiter-tui[report]' (from a clone: pip install -e '.[report]')"
SUFFIXES = (".svg", ".png")


def _pyplot() -> Any:
    """matplotlib.pyplot on the headless Agg backend; ImportError (with how to install) when missing."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError(f"needs matplotlib: {INSTALL}") from None
    return plt


def cannot_plot(path: Path) -> str | None:
    """Why the figure could not be written to ``path``, in words, or None: asked before a sweep runs, so
    a long sweep never ends in a plot that fails. Nothing is left behind (an existing file is opened to
    append nothing, a new one is tried in its directory and removed)."""
    if path.suffix.lower() not in SUFFIXES:
        return "give a .svg or .png file"
    if path.is_dir():
        return "a directory, not a file"
    if path.exists() and not path.is_file():
        return "not a regular file"  # a FIFO would block the check, a device take the image
    directory = path.parent
    if not directory.is_dir():
        return f"no such directory: {directory}"
    if path.exists():
        try:
            with open(path, "ab"):
                pass
        except OSError:
            return NOT_WRITABLE
    elif not can_create_in(directory):
        return f"{directory}: {NOT_WRITABLE}"
    try:
        _pyplot()
    except ImportError as exc:
        return str(exc)
    return None


def figure(cells: list[SweepCell]) -> Figure:
    """The figure: one panel per mission, and one legend for them all to the right of the panels, off
    the data (inside a panel it covered the points at the longest latencies). ImportError (with how to
    install) when matplotlib is missing."""
    plt = _pyplot()
    data = series(cells)
    n = len(data)
    cols = min(n, 2)
    rows = math.ceil(n / cols)
    fig: Figure
    fig, axes = plt.subplots(rows, cols, figsize=(6.0 * cols, 4.0 * rows), squeeze=False)
    first = cells[0].link
    for ax, (mission, lines) in zip(axes.flat, data.items(), strict=False):
        for algorithm, points in lines.items():
            x = [p[0] for p in points]
            y = [p[1] for p in points]
            style = style_of(algorithm)  # the marker and colour it has on the console's plots
            ax.plot(x, y, marker=style.mpl_marker, color=style.mpl_colour, label=algorithm)
            if any(p[2] for p in points):
                lo, hi = [p[1] - p[2] for p in points], [p[1] + p[2] for p in points]
                ax.fill_between(x, lo, hi, color=style.mpl_colour, alpha=0.2)
        ax.set_title(mission)
        ax.set_xlabel("one-way command latency (ms)")
        ax.set_ylabel("avg cross-track error (m)")
        ax.grid(True, alpha=0.3)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    trials = len(cells[0].runs)
    fig.suptitle(
        f"arbiter-tui compare: jitter {first.jitter_s * 1e3:g} ms, loss {first.loss:g}, odometry delay "
        f"{first.odom_delay_s * 1e3:g} ms, {trials} trial(s)"
        + (", bands: 95 % interval" if trials > 1 else "")
    )
    fig.tight_layout()
    # every panel has the same controllers in the same colours: one legend, outside every panel (the
    # saved image grows to hold it: bbox_inches="tight")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.0, 0.95), fontsize="small")
    return fig


def write_plot(path: Path, cells: list[SweepCell]) -> None:
    """Write the figure as SVG or PNG (by the suffix); ImportError (with how to install) when matplotlib
    is missing."""
    fig = figure(cells)
    plt = _pyplot()
    try:
        fig.savefig(path, format=path.suffix.lower().lstrip("."), bbox_inches="tight")
    finally:
        plt.close(fig)
