"""Path-tracking metrics of a run, beside the seed's nine AnalyticsStats (which stay as the seed has them).

Pure: numpy and ``arbiter_core.stats``; no I/O, no Textual. One definition, used by the analytics
screen, ``arbiter-tui compare`` and the exports.

The **reference path** of a mission run is the polyline from where the run started through every
waypoint in order (a goal run: the straight segment from its start to the goal). For samples
``i = 0..n-1`` at times ``t_i`` with positions ``p_i``, commanded speeds ``v_i`` and turn rates ``w_i``:

* cross-track error ``e_i = min over the path's segments of the distance from p_i to the segment``;
  reported as its mean, RMS ``sqrt(sum e_i^2 / n)``, p95 (the seed's rule: sorted, index
  ``floor(0.95 n)``) and max;
* time to complete: the run's time from start to end, only for a completed run;
* path-length ratio: the distance the robot travelled (the seed's ``totalPathLength`` of the run) over
  the reference path's length (1.0 = no detour);
* smoothness, mean ``|dw/dt|``: ``sum |w_{i+1} - w_i| / (t_{i+1} - t_i)`` over consecutive samples with
  a positive time step, divided by their count, in rad/s² (0 = a constant turn rate);
* integrated jerk (navigation2 #3239's smoothness), linear and angular: the commanded velocity ``u`` (``v``
  or ``w``) differentiated twice by finite differences over the samples' own times, squared and
  integrated: with ``a_k = (u_{k+1} - u_k) / (t_{k+1} - t_k)`` at the midpoints ``m_k``, ``j_k = (a_{k+1}
  - a_k) / (m_{k+1} - m_k)``, the figure is ``sum j_k^2 (m_{k+1} - m_k)``, in m²/s⁵ (linear) and rad²/s⁵
  (angular); steps with no time are skipped. 0 for a constant command; a stop from full speed within
  one sample counts, so compare runs sampled at the same rate;
* success: 1 when the run completed (reached its goal within the mission's tolerance) within its time
  limit, ``time_limit_s(reference) = GRACE_S + reference length / MIN_PROGRESS_MPS`` (10 s plus 10 s a
  metre: a run averaging less than 0.1 m/s along its reference failed), else 0; several runs: the
  fraction that succeeded (the success rate).

Path length is the seed's ``totalPathLength`` (``AnalyticsStats``), not repeated here.
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
    "mean_abs_dw_dt", "linear_jerk", "angular_jerk", "success",
)  # fmt: skip
ADDED_LATER = ("linear_jerk", "angular_jerk", "success")  # None in files written before they existed
OPTIONAL = ("time_to_complete_s", "path_ratio", *ADDED_LATER)
GRACE_S = 10.0
MIN_PROGRESS_MPS = 0.1


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
    linear_jerk: float | None = None  # m^2/s^5; None: read from a file that predates it
    angular_jerk: float | None = None  # rad^2/s^5
    success: float | None = None  # 1/0 for a run, the success rate for several

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
            if v is None and f in OPTIONAL:
                values[f] = None
                continue
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"tracking.{f} must be a finite number")
            if f == "success" and not 0.0 <= v <= 1.0:
                raise ValueError("tracking.success must be between 0 and 1")
            values[f] = float(v)
        return cls(samples, **values)  # type: ignore[arg-type]  # checked above: None only where OPTIONAL


def reference_path(start: Point, waypoints: Sequence[Point]) -> np.ndarray:
    """The polyline a run should follow: its start, then every waypoint; shape (k, 2)."""
    return np.array([start, *waypoints], dtype=np.float64).reshape(-1, 2)


def path_length(path: np.ndarray) -> float:
    """The length of a polyline of shape (k, 2) (``arbiter_core.stats.path_length``)."""
    return S.path_length(path[:, 0], path[:, 1])


def cross_track(x: np.ndarray, y: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Each sample's distance to the nearest point of the polyline ``path`` (one point: to that point).
    O(samples · log poses) on a path that does not pass near a sample many times: see :class:`PathIndex`."""
    return PathIndex(path).distances(x, y)


def segment_distance(
    px: np.ndarray, py: np.ndarray, ax: np.ndarray, ay: np.ndarray, dx: np.ndarray, dy: np.ndarray
) -> np.ndarray:
    """Distance from each point ``p`` to the segment ``a + u d``, ``0 <= u <= 1`` (element-wise, broadcast);
    a segment of no length is its point. The one definition of a sample's distance to a segment."""
    seg2 = dx * dx + dy * dy
    safe = np.where(seg2 > 0, seg2, 1.0)
    u = np.clip(((px - ax) * dx + (py - ay) * dy) / safe, 0.0, 1.0)
    u = np.where(seg2 > 0, u, 0.0)
    ex = px - (ax + u * dx)
    ey = py - (ay + u * dy)
    distance: np.ndarray = np.sqrt(ex * ex + ey * ey)
    return distance


class PathIndex:
    """A polyline's segments in a tree of bounding boxes, for the distance from many points to it.

    The tree is built over the segments *in path order* (no sorting: a path is spatially coherent, so
    consecutive segments make tight boxes): level 0 holds each segment's box, level ``l + 1`` the boxes of
    pairs of level ``l``. A query walks down from the root for all its points at once, keeping for each
    point only the nodes whose box is nearer than the nearest path *vertex* seen so far (a vertex of a
    node is a point of the path: no nearer segment can lie in a box farther than it), and takes the exact
    distance (:func:`segment_distance`) to the segments that remain. The answer is the brute-force minimum
    over every segment, to the last bit: the segments dropped cannot hold it.

    Cost: building O(k) for k poses; a query O(log k) levels times the nodes per level whose boxes come
    within the sample's error of it (a handful, unless the path passes within that distance of the sample
    many times: then up to every segment, as a brute force would). Memory: O(k) for the tree, and the
    pairs (point, node) still in play, worked through in batches of at most ``BATCH_PAIRS``.
    """

    BRUTE_MAX = 16  # segments: fewer are measured against every point directly
    BATCH_PAIRS = 1 << 20

    def __init__(self, path: np.ndarray) -> None:
        path = np.asarray(path, dtype=np.float64).reshape(-1, 2)
        if not len(path):
            raise ValueError("a path needs at least one point")
        self.path = path
        a = path[:-1]
        d = path[1:] - a
        self._a, self._d = a, d
        self.levels: list[np.ndarray] = []  # each (4, nodes): min x, min y, max x, max y
        if len(a) > self.BRUTE_MAX:
            box = np.stack((np.minimum(a[:, 0], path[1:, 0]), np.minimum(a[:, 1], path[1:, 1]),
                            np.maximum(a[:, 0], path[1:, 0]), np.maximum(a[:, 1], path[1:, 1])))  # fmt: skip
            self.levels.append(box)
            while box.shape[1] > 1:
                if box.shape[1] % 2:
                    box = np.concatenate((box, box[:, -1:]), axis=1)  # the odd one paired with itself
                box = np.concatenate((np.minimum(box[:2, 0::2], box[:2, 1::2]),
                                      np.maximum(box[2:, 0::2], box[2:, 1::2])))  # fmt: skip
                self.levels.append(box)

    def distances(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        px = np.asarray(x, dtype=np.float64).ravel()
        py = np.asarray(y, dtype=np.float64).ravel()
        if len(self.path) == 1:
            to_point: np.ndarray = np.hypot(px - self.path[0, 0], py - self.path[0, 1])
            return to_point
        out = np.empty(px.size, dtype=np.float64)
        if not self.levels:
            step = max(1, self.BATCH_PAIRS // len(self._a))
            a, d = self._a, self._d
            for i in range(0, px.size, step):
                e = segment_distance(px[i : i + step, None], py[i : i + step, None], a[:, 0], a[:, 1],
                                     d[:, 0], d[:, 1])  # fmt: skip
                out[i : i + step] = e.min(axis=1)
            return out
        pending = [np.arange(px.size)]
        while pending:
            idx = pending.pop()
            if idx.size and not self._query(px, py, idx, out):
                half = idx.size // 2  # too many pairs in play at once: each half on its own
                pending += [idx[:half], idx[half:]]
        return out

    def _query(self, px: np.ndarray, py: np.ndarray, idx: np.ndarray, out: np.ndarray) -> bool:
        """The distances of the points ``idx`` into ``out``; False (nothing written) when the pairs in
        play would exceed ``BATCH_PAIRS`` and ``idx`` can be split."""
        top = len(self.levels) - 1
        who = np.arange(idx.size)  # pairs: which of the batch's points ...
        node = np.zeros(idx.size, dtype=np.int64)  # ... against which node of the current level
        qx, qy = px[idx], py[idx]
        for level in range(top, -1, -1):
            if level < top:  # each pair becomes one pair per child of its node
                n = self.levels[level].shape[1]
                who = np.repeat(who, 2)
                node = np.repeat(node * 2, 2)
                node[1::2] += 1
                keep = node < n
                who, node = who[keep], node[keep]
            if who.size > self.BATCH_PAIRS and idx.size > 1:
                return False
            box = self.levels[level]
            bx, by = qx[who], qy[who]
            gx = np.maximum(np.maximum(box[0, node] - bx, bx - box[2, node]), 0.0)
            gy = np.maximum(np.maximum(box[1, node] - by, by - box[3, node]), 0.0)
            low = np.sqrt(gx * gx + gy * gy)  # no point of the node's segments is nearer
            first = self.path[node << level]  # the node's first vertex: a point of the path
            high = np.hypot(bx - first[:, 0], by - first[:, 1])
            bound = np.full(idx.size, np.inf)
            np.minimum.at(bound, who, high)
            # margin: rounding must never drop the segment the exact formula finds nearest
            keep = low <= bound[who] * (1.0 + 1e-9) + 1e-9
            who, node = who[keep], node[keep]
        a, d = self._a[node], self._d[node]
        e = segment_distance(qx[who], qy[who], a[:, 0], a[:, 1], d[:, 0], d[:, 1])
        best = np.full(idx.size, np.inf)
        np.minimum.at(best, who, e)
        out[idx] = best
        return True


def mean_abs_rate(t_s: np.ndarray, w: np.ndarray) -> float:
    """Mean ``|dw/dt|`` over consecutive samples with a positive time step (0 with fewer than two)."""
    dt = np.diff(np.asarray(t_s, dtype=np.float64))
    dw = np.abs(np.diff(np.asarray(w, dtype=np.float64)))
    ok = dt > 0
    return S.mean(dw[ok] / dt[ok]) if ok.any() else 0.0


def integrated_jerk(t_s: np.ndarray, u: np.ndarray) -> float:
    """``sum j_k^2 (m_{k+1} - m_k)`` of a commanded velocity ``u`` over times ``t_s`` (the module's
    formula); 0 with fewer than three samples at distinct times."""
    t = np.asarray(t_s, dtype=np.float64)
    v = np.asarray(u, dtype=np.float64)
    keep = np.concatenate(([True], np.diff(t) > 0)) if t.size else t.astype(bool)
    t, v = t[keep], v[keep]
    if t.size < 3:
        return 0.0
    dt = np.diff(t)
    a = np.diff(v) / dt
    m = t[:-1] + dt / 2
    dm = np.diff(m)
    j = np.diff(a) / dm
    return float(np.sum(j * j * dm))


def time_limit_s(reference_m: float) -> float:
    """How long a run along a reference of this length may take and still count as a success."""
    return GRACE_S + reference_m / MIN_PROGRESS_MPS


def succeeded(completed_time_s: float | None, reference_m: float) -> float:
    return 1.0 if completed_time_s is not None and completed_time_s <= time_limit_s(reference_m) else 0.0


def of_errors(
    xte: np.ndarray,
    travelled: float,
    reference_m: float,
    completed_time_s: float | None,
    dw_dt: float,
    jerks: tuple[float, float] | None = None,
    success: float | None = None,
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
        linear_jerk=None if jerks is None else jerks[0],
        angular_jerk=None if jerks is None else jerks[1],
        success=success,
    )


def tracking_stats(
    t_s: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    path: np.ndarray,
    travelled: float,
    completed_time_s: float | None,
) -> TrackingStats:
    """A run's tracking metrics from its time-ordered samples: positions, commanded speeds and turn
    rates, against one reference path (see the module for each formula)."""
    return tracking_of(t_s, v, w, cross_track(x, y, path), path_length(path), travelled, completed_time_s)


def tracking_of(
    t_s: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    xte: np.ndarray,
    reference_m: float,
    travelled: float,
    completed_time_s: float | None,
) -> TrackingStats:
    """A run's tracking metrics from its samples' cross-track errors already measured (each against the
    reference in force when it was taken) and the length of its first reference."""
    jerks = (integrated_jerk(t_s, v), integrated_jerk(t_s, w))
    return of_errors(xte, travelled, reference_m, completed_time_s, mean_abs_rate(t_s, w), jerks,
                     succeeded(completed_time_s, reference_m))  # fmt: skip


def mean_of(values: Sequence[float | None]) -> float | None:
    """The mean of the values that are known; None when none is."""
    known = [v for v in values if v is not None]
    return sum(known) / len(known) if known else None


def pooled(runs: Sequence[tuple[np.ndarray, TrackingStats, float]]) -> TrackingStats | None:
    """Several runs of one algorithm on one mission together: the cross-track figures over their pooled
    errors; time to complete, path ratio, the jerks and success averaged over the runs that have them
    (success: the success rate); smoothness weighted by samples.
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
        mean_of([s.linear_jerk for _e, s, _n in runs]),
        mean_of([s.angular_jerk for _e, s, _n in runs]),
        mean_of([s.success for _e, s, _n in runs]),
    )  # fmt: skip
