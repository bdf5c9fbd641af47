"""Error against latency for the live analytics screen: a sweep's curve per controller, and where the
latency this console measures right now falls on it. Pure: no I/O, no Textual.

The curve comes from ``arbiter-tui compare --json --latency ...`` (one mission, every controller); the
value at a latency between two swept ones is interpolated linearly, beyond the last one it is the
last one (and said to be). "At your p95 of 4 ms: go_to_goal +0.00 m" is the controller's avg
cross-track error at that latency minus its error at 0 ms (the first swept latency).
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from arbiter_core import stats as S

SWEEP_LATENCIES_MS = (0.0, 50.0, 100.0, 200.0, 300.0, 500.0)
IDLE, RUNNING, READY, FAILED = "idle", "running", "ready", "failed"
SWEEP_RETRY_S = 30.0  # a failed sweep is tried again this long after, while the analytics screen shows


class CurveError(ValueError):
    """A compare answer that does not hold a sweep."""


@dataclass(frozen=True, slots=True)
class LinkCurve:
    mission: str
    latencies_ms: tuple[float, ...]
    errors: tuple[tuple[str, tuple[float, ...]], ...]  # (controller, avg e_xt at each latency)

    def at(self, ms: float) -> tuple[tuple[str, float], ...]:
        """Each controller's avg e_xt at ``ms`` minus its error at the first swept latency (to the mm)."""
        return tuple(
            (name, round(interpolate(self.latencies_ms, ys, ms) - ys[0], 3) + 0.0) for name, ys in self.errors
        )


def interpolate(xs: Sequence[float], ys: Sequence[float], x: float) -> float:
    """Linear between the neighbours of ``x``; the end value outside ``xs`` (sorted ascending)."""
    if x <= xs[0]:
        return ys[0]
    for (x0, y0), (x1, y1) in zip(zip(xs, ys, strict=True), zip(xs[1:], ys[1:], strict=True), strict=False):
        if x <= x1:
            return y0 + (y1 - y0) * (x - x0) / (x1 - x0) if x1 > x0 else y1
    return ys[-1]


def curve_of(body: Any, mission: str) -> LinkCurve:
    """The curve of ``mission`` in a ``compare --json`` sweep answer (``sweep`` cells, one per latency)."""
    try:
        cells = sorted(body["sweep"], key=lambda c: float(c["link"]["latency_ms"]))
        latencies = tuple(float(c["link"]["latency_ms"]) for c in cells)
        errors: dict[str, list[float]] = {}
        for cell in cells:
            for m in cell["missions"]:
                if m["mission"] != mission:
                    continue
                for entry in m["ranking"]:
                    errors.setdefault(str(entry["algorithm"]), []).append(float(entry["xte_mean_m"]["mean"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise CurveError(f"not a compare sweep: {type(exc).__name__}: {exc}") from None
    if not latencies or not errors or any(len(v) != len(latencies) for v in errors.values()):
        raise CurveError(f"the sweep holds no complete curve for {mission!r}")
    if any(not math.isfinite(v) for ys in errors.values() for v in ys):
        raise CurveError("the sweep holds an error that is not a finite number")
    return LinkCurve(mission, latencies, tuple((k, tuple(v)) for k, v in errors.items()))


def measured_p95(latencies_ms: Sequence[float] | np.ndarray) -> float | None:
    """The p95 (the product's rule) of the one-way latencies the console recorded; None without any.
    A negative one (clocks apart) counts as 0, as ``compare --latency measured`` does. Vectorised: the
    ring can hold a million samples."""
    a = np.asarray(latencies_ms, dtype=np.float64)
    a = a[np.isfinite(a)]
    return S.p95(np.maximum(a, 0.0)) if a.size else None


@dataclass(frozen=True, slots=True)
class LinkSweepView:
    """What the analytics screen's error-vs-latency plot and its line show."""

    state: str = IDLE
    mission: str = ""
    curve: LinkCurve | None = None
    p95_ms: float | None = None
    error: str = ""
    paused: bool = False  # the sweep waits while the robot drives (a console with no core to spare)

    def text(self, width: int | None = None, rows: int = 2) -> str:
        """In words; with ``width``, fitted to ``rows`` lines of that many cells (word-wrapped): the
        controllers that do not fit are left out whole, and an ellipsis says so."""
        if self.state == RUNNING and self.paused:
            return "latency sweep paused while the robot drives: no core to spare (goes on once it stops)"
        if self.state == RUNNING:
            return f"sweeping latency {_range()} for {self.mission} in the background (arbiter-tui compare)…"
        if self.state == FAILED:
            return f"latency sweep failed: {self.error} (tried again in {SWEEP_RETRY_S:g} s)"
        if self.curve is None:
            return "error vs latency: shown once the sweep has run (it starts when this screen opens)"
        if self.p95_ms is None:
            return f"{self.curve.mission}: no latency measured yet (simulated link, or nothing recorded)"
        beyond = " (beyond the sweep: its last value)" if self.p95_ms > self.curve.latencies_ms[-1] else ""
        parts = [f"{name} {delta + 0.0:+.3f} m" for name, delta in self.curve.at(round(self.p95_ms))]
        where = f"at your p95 of {format_ms(self.p95_ms)} ms{beyond} on {self.curve.mission}"
        full = f"{where}: {', '.join(parts)} (avg e_xt vs 0 ms)"
        if width is None or _fits(full, width, rows):
            return full
        for keep in range(len(parts) - 1, 0, -1):
            cut = f"{where}: {', '.join(parts[:keep])}, … (avg e_xt vs 0 ms)"
            if _fits(cut, width, rows):
                return cut
        return f"{where}: {parts[0]}, …"


def _fits(text: str, width: int, rows: int) -> bool:
    return len(textwrap.wrap(text, max(width, 1))) <= rows


def format_ms(value: float) -> str:
    """0.4 (a LAN link) or 130: a tenth of a millisecond only where it is most of the figure. The one
    format of the measured p95 on the analytics screen: the plot's legend and the line under it."""
    return f"{value:.1f}" if value < 10 else f"{value:.0f}"


def _range() -> str:
    return f"{SWEEP_LATENCIES_MS[0]:g}-{SWEEP_LATENCIES_MS[-1]:g} ms"
