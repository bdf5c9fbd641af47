"""Path-tracking metrics of a run, beside the seed's nine AnalyticsStats (which stay as the seed has them).

Pure: numpy and ``arbiter_core.stats``; no I/O, no Textual. One definition, used by the analytics
screen, ``arbiter-tui compare`` and the exports.

The **reference path** of a mission run is the polyline from where the run started through every
waypoint in order (a goal run: the straight segment from its start to the goal). For samples
``i = 0..n-1`` at times ``t_i`` with positions ``p_i`` and commanded turn rates ``w_i``:

* cross-track error ``e_i = min over the path's segments of the distance from p_i to the segment``;
  reported as its mean, RMS ``sqrt(sum e_i^2 / n)``, p95 (the seed's rule: sorted, index
  ``floor(0.95 n)``) and max;
* time to complete: the run's time from start to end, only for a completed run;
* path-length ratio: the distance the robot travelled (the seed's ``totalPathLength`` of the run) over
  the reference path's length (1.0 = no detour);
* smoothness, mean ``|dw/dt|``: ``sum |w_{i+1} - w_i| / (t_{i+1} - t_i)`` over consecutive samples with
  a positive time step, divided by their count, in rad/s² (0 = a constant turn rate).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from arbiter_core import stats as S

Point = tuple[float, float]

TRACKING_FIELDS = (
    "xte_mean_m", "xte_rms_m", "xte_p95_m", "xte_max_m", "time_to_complete_s", "path_ratio",
    "mean_abs_dw_dt",
)  # fmt: skip


@dataclass(frozen=True, slots=True)
class TrackingStats:
    samples: int
    xte_mean_m: float
    xte_rms_m: float
    xte_p95_m: float
    xte_max_m: float
    time_to_complete_s: float | None  # None unless the run completed
    path_ratio: float | None  # None when the reference has no length
    mean_abs_dw_dt: float  # rad/s^2

    def as_dict(self) -> dict[str, Any]:
        def r(v: float | None) -> float | None:
            return None if v is None else round(v, 6)

        return {"samples": self.samples, **{f: r(getattr(self, f)) for f in TRACKING_FIELDS}}

    @classmethod
    def from_dict(cls, raw: Any) -> TrackingStats:
        """The inverse of :meth:`as_dict`; ValueError naming the field that is wrong."""
        if not isinstance(raw, dict):
            raise ValueError("tracking must be an object")
        samples = raw.get("samples")
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 0:
            raise ValueError("tracking.samples must be a count")
        values: dict[str, float | None] = {}
        for f in TRACKING_FIELDS:
            v = raw.get(f)
            optional = f in ("time_to_complete_s", "path_ratio")
            if v is None and optional:
                values[f] = None
                continue
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"tracking.{f} must be a finite number")
            values[f] = float(v)
        return cls(samples, **values)  # type: ignore[arg-type]


def reference_path(start: Point, waypoints: Sequence[Point]) -> np.ndarray:
    """The polyline a run should follow: its start, then every waypoint; shape (k, 2)."""
    return np.array([start, *waypoints], dtype=np.float64).reshape(-1, 2)


def path_length(path: np.ndarray) -> float:
    """The length of a polyline of shape (k, 2) (``arbiter_core.stats.path_length``)."""
    return S.path_length(path[:, 0], path[:, 1])


def cross_track(x: np.ndarray, y: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Each sample's distance to the nearest point of the polyline ``path`` (one point: to that point)."""
    px = np.asarray(x, dtype=np.float64)[:, None]
    py = np.asarray(y, dtype=np.float64)[:, None]
    if len(path) == 1:
        return np.hypot(px[:, 0] - path[0, 0], py[:, 0] - path[0, 1])
    a = path[:-1]
    d = path[1:] - a
    seg2 = (d * d).sum(axis=1)
    safe = np.where(seg2 > 0, seg2, 1.0)
    u = np.clip(((px - a[:, 0]) * d[:, 0] + (py - a[:, 1]) * d[:, 1]) / safe, 0.0, 1.0)
    u = np.where(seg2 > 0, u, 0.0)
    dx = px - (a[:, 0] + u * d[:, 0])
    dy = py - (a[:, 1] + u * d[:, 1])
    return np.sqrt((dx * dx + dy * dy).min(axis=1))


def mean_abs_rate(t_s: np.ndarray, w: np.ndarray) -> float:
    """Mean ``|dw/dt|`` over consecutive samples with a positive time step (0 with fewer than two)."""
    dt = np.diff(np.asarray(t_s, dtype=np.float64))
    dw = np.abs(np.diff(np.asarray(w, dtype=np.float64)))
    ok = dt > 0
    return S.mean(dw[ok] / dt[ok]) if ok.any() else 0.0


def of_errors(
    xte: np.ndarray, travelled: float, reference_m: float, completed_time_s: float | None, dw_dt: float
) -> TrackingStats:
    """TrackingStats from cross-track errors already computed (a run's, or several runs' pooled)."""
    e = np.asarray(xte, dtype=np.float64)
    n = int(e.size)
    return TrackingStats(
        samples=n,
        xte_mean_m=S.mean(e),
        xte_rms_m=math.sqrt(S.mean(e * e)) if n else 0.0,
        xte_p95_m=S.p95(e),
        xte_max_m=S.maximum(e) if n else 0.0,
        time_to_complete_s=completed_time_s,
        path_ratio=travelled / reference_m if reference_m > 0 else None,
        mean_abs_dw_dt=dw_dt,
    )


def tracking_stats(
    t_s: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
    w: np.ndarray,
    path: np.ndarray,
    travelled: float,
    completed_time_s: float | None,
) -> TrackingStats:
    """A run's tracking metrics from its time-ordered samples (see the module for each formula)."""
    return of_errors(cross_track(x, y, path), travelled, path_length(path), completed_time_s,
                     mean_abs_rate(t_s, w))  # fmt: skip


def pooled(runs: Sequence[tuple[np.ndarray, TrackingStats, float]]) -> TrackingStats | None:
    """Several runs of one algorithm on one mission together: the cross-track figures over their pooled
    errors; time to complete, path ratio and smoothness averaged over the runs that have them.
    ``runs``: (cross-track errors, the run's TrackingStats, its weight for smoothness = samples)."""
    if not runs:
        return None
    errors = np.concatenate([e for e, _s, _n in runs])
    times = [s.time_to_complete_s for _e, s, _n in runs if s.time_to_complete_s is not None]
    ratios = [s.path_ratio for _e, s, _n in runs if s.path_ratio is not None]
    weight = sum(n for _e, _s, n in runs)
    smooth = sum(s.mean_abs_dw_dt * n for _e, s, n in runs) / weight if weight else 0.0
    base = of_errors(errors, 0.0, 0.0, None, smooth)
    return TrackingStats(
        base.samples, base.xte_mean_m, base.xte_rms_m, base.xte_p95_m, base.xte_max_m,
        sum(times) / len(times) if times else None,
        sum(ratios) / len(ratios) if ratios else None,
        smooth,
    )  # fmt: skip
