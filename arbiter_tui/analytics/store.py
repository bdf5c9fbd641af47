"""The analytics store: the seed's ``useAnalyticsEngine``.

The seed keeps its refs at module level so that data survives page navigation; here the robot
session (``session/robot.py``) owns one store, shared by every screen, so data survives screen switches
and a second session (another robot, a test) has its own. It is a circular buffer of
:class:`DataPoint` held column-wise in numpy arrays (9 float64 columns, a one-byte
algorithm code, a four-byte run id and a one-byte gap mark: 78 bytes per point), grown on demand up to
``max_data_points``, so statistics over a million points take milliseconds.

Who writes it: the robot session's thread (the control loop samples odometry
from the link's telemetry at the collection rate; roslibpy's Twisted thread
writes telemetry, never the store); the shell reads it at its own pace. It takes
a lock, so readers and writers on different threads see consistent data (tests/unit
exercise concurrent writers).
"""

from __future__ import annotations

import math
import threading

import numpy as np

from arbiter_core import stats as S

from .model import (
    EMPTY_STATS,
    FIELDS,
    MAX_ALGORITHM_NAME,
    NUMERIC,
    STATS_FIELDS,
    AnalyticsStats,
    DataPoint,
    compute_stats,
    grouped_stats,
    stats_of_points,
)
from .runs import AlgorithmSummary, RunLog, RunSummary

_COL = {name: i for i, name in enumerate(NUMERIC)}
MAX_CAPACITY = 10_000_000


def _wrapped(size: int, cap: int, nxt: int) -> bool:
    """True when the ring is full and its oldest point is not in slot 0."""
    return size == cap and nxt != 0


def _order(size: int, cap: int, nxt: int) -> np.ndarray | slice:
    """Indices of the stored points, oldest first."""
    if not _wrapped(size, cap, nxt):
        return slice(0, size)
    wrapped: np.ndarray = np.r_[nxt:size, 0:nxt]
    return wrapped


def _last(size: int, cap: int, nxt: int, n: int | None) -> np.ndarray | slice:
    """Indices of the newest ``n`` stored points (all when None), oldest first: O(n), not O(ring)."""
    k = size if n is None else max(0, min(n, size))
    if not _wrapped(size, cap, nxt):
        return slice(size - k, size)
    if k <= nxt:  # nxt holds the oldest point; the newest is at nxt - 1
        return slice(nxt - k, nxt)
    wrapped: np.ndarray = np.r_[size - (k - nxt) : size, 0:nxt]
    return wrapped


class AnalyticsStore:
    def __init__(self, max_data_points: int = 1000, collection_rate: float = 10.0) -> None:
        self._lock = threading.RLock()
        self._version = 0
        self._is_collecting = False
        self._collection_rate = 10.0
        self._max = 1
        self._algos: list[str] = []
        self._algo_index: dict[str, int] = {}
        self._runs = RunLog()
        self._reset_buffers(0)
        self.total_recorded = 0  # points recorded since start, including those the ring has dropped
        self.clears = 0  # times :meth:`clear` forgot everything (a journal starts a new file then)
        self.collection_rate = collection_rate
        self.max_data_points = max_data_points

    # -- buffer management -------------------------------------------------
    def _reset_buffers(self, alloc: int) -> None:
        self._num = np.empty((len(NUMERIC), alloc), dtype=np.float64)
        self._alg = np.empty(alloc, dtype=np.uint8)
        self._run = np.empty(alloc, dtype=np.uint32)  # run id, 0 outside every run
        self._gap = np.empty(alloc, dtype=np.bool_)  # the sample follows a gap in the recording
        self._size = 0
        self._next = 0

    def _grow(self) -> None:
        alloc = self._num.shape[1]
        new = min(self._max, max(1024, alloc * 2))
        num = np.empty((len(NUMERIC), new), dtype=np.float64)
        alg = np.empty(new, dtype=np.uint8)
        run = np.empty(new, dtype=np.uint32)
        gap = np.empty(new, dtype=np.bool_)
        num[:, : self._size] = self._num[:, : self._size]
        alg[: self._size] = self._alg[: self._size]
        run[: self._size] = self._run[: self._size]
        gap[: self._size] = self._gap[: self._size]
        self._num, self._alg, self._run, self._gap = num, alg, run, gap

    # -- settings ----------------------------------------------------------
    @property
    def is_collecting(self) -> bool:
        return self._is_collecting

    @property
    def collection_rate(self) -> float:
        return self._collection_rate

    @collection_rate.setter
    def collection_rate(self, hz: float) -> None:
        if (
            isinstance(hz, bool)
            or not isinstance(hz, (int, float))
            or not math.isfinite(hz)
            or not 0 < hz <= 1000
        ):
            raise ValueError(f"collection_rate must be in (0, 1000] Hz, got {hz!r}")
        self._collection_rate = float(hz)

    @property
    def max_data_points(self) -> int:
        return self._max

    @max_data_points.setter
    def max_data_points(self, n: int) -> None:
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_CAPACITY:
            raise ValueError(f"max_data_points must be an integer in [1, {MAX_CAPACITY}], got {n!r}")
        with self._lock:
            if n != self._max:
                order = _order(self._size, self._max, self._next)
                keep_num = self._num[:, order][:, -n:] if self._size else self._num[:, :0]
                keep_alg = self._alg[order][-n:] if self._size else self._alg[:0]
                keep_gap = self._gap[order][-n:] if self._size else self._gap[:0]
                all_runs = self._run[order] if self._size else self._run[:0]
                keep_run = all_runs[-n:]
                dropped = all_runs[: max(0, all_runs.size - n)]
                for run_id, count in zip(*np.unique(dropped, return_counts=True), strict=True):
                    if run_id:
                        self._runs.evicted(int(run_id), int(count))
                self._max = n
                k = keep_num.shape[1]
                self._reset_buffers(min(n, max(1024, k)))
                self._num[:, :k] = keep_num
                self._alg[:k] = keep_alg
                self._run[:k] = keep_run
                self._gap[:k] = keep_gap
                self._size = k
                self._next = k % self._num.shape[1] if k == n else k
                self._version += 1

    # -- collection ----------------------------------------------------------
    @property
    def version(self) -> int:
        """Changes whenever anything a reader sees changes (points, clearing, collecting on/off)."""
        return self._version

    def start_collection(self) -> None:
        self._is_collecting = True
        self._version += 1

    def stop_collection(self) -> None:
        self._is_collecting = False
        self._version += 1

    def clear(self) -> None:
        """Forget every point and every run (a run in progress goes on, from now)."""
        with self._lock:
            self._reset_buffers(0)
            self._runs.clear()
            self.clears += 1
            self._version += 1

    # -- runs ----------------------------------------------------------------------------------
    def begin_run(
        self,
        algorithm: str,
        mission: str,
        t_ms: float,
        path: np.ndarray | None = None,
        stand_in: bool = False,
    ) -> int:
        """Start a run (an active one ends as aborted); points recorded with its id join it. ``path``:
        its reference path, for the tracking metrics (``analytics.tracking``); ``stand_in``: only until
        the run's first plan comes (:meth:`follow_path`)."""
        with self._lock:
            run_id = self._runs.begin(algorithm, mission, t_ms, path, stand_in)
            self._version += 1
        return run_id

    def follow_path(self, path: np.ndarray) -> None:
        """The active run's reference from its next sample on: the plan its controller now follows."""
        with self._lock:
            self._runs.follow(path)
            self._version += 1

    def end_run(
        self, outcome: str, t_ms: float, final_error_m: float | None = None, drop_later: bool = False
    ) -> RunSummary | None:
        """End the active run at ``t_ms``. ``drop_later``: its samples taken after ``t_ms`` leave it (they
        stay in the store, in no run): a run found, later, to have ended earlier."""
        with self._lock:
            active = self._runs.active
            if drop_later and active is not None and self._runs.drop_after(t_ms):
                self._detach_after(active, t_ms)
            summary = self._runs.end(outcome, t_ms, final_error_m)
            if summary is not None:
                self._version += 1
        return summary

    def _detach_after(self, run_id: int, t_ms: float) -> None:
        """The newest stored points of ``run_id`` taken after ``t_ms`` belong to no run."""
        alloc = self._num.shape[1]
        i = self._next - 1
        for _ in range(self._size):
            i %= alloc
            if self._run[i] != run_id or self._num[0, i] <= t_ms:
                break
            self._run[i] = 0
            i -= 1

    @property
    def active_run(self) -> int | None:
        return self._runs.active

    def runs(self) -> tuple[RunSummary, ...]:
        """Every run with samples, oldest first: summaries over all their samples (not just the ring's)."""
        with self._lock:
            return self._runs.summaries()

    def run(self, run_id: int) -> RunSummary | None:
        with self._lock:
            return self._runs.get(run_id)

    def runs_by_algorithm(self) -> tuple[AlgorithmSummary, ...]:
        with self._lock:
            return self._runs.by_algorithm()

    def record(self, point: DataPoint) -> bool:
        """Store a point if collection is on; returns whether it was stored.

        Raises ValueError for a point with a missing, non-numeric or non-finite value.
        """
        point.validate()
        if not self._is_collecting:
            return False
        with self._lock:
            code = self._algo_index.get(point.algorithm)
            if code is None:
                if len(self._algos) >= 255:
                    raise ValueError("too many distinct algorithm names (255)")
                code = len(self._algos)
                self._algos.append(point.algorithm)
                self._algo_index[point.algorithm] = code
            if self._size == self._num.shape[1] and self._size < self._max:
                self._grow()
            i = self._next
            if self._size == self._max:  # the ring is full: slot i holds the oldest point, dropped now
                old = int(self._run[i])
                if old:
                    self._runs.evicted(old)
            run_id = point.runId or 0
            if run_id and not self._runs.add(
                run_id, point.timestamp, point.x, point.y, point.linearVel, point.angularVel,
                point.distanceError, point.headingError, point.gap,
            ):  # fmt: skip
                run_id = 0  # not the active run: kept as a plain sample
            col = self._num[:, i]
            col[0] = point.timestamp
            col[1] = point.x
            col[2] = point.y
            col[3] = point.theta
            col[4] = point.linearVel
            col[5] = point.angularVel
            col[6] = point.distanceError
            col[7] = point.headingError
            col[8] = math.nan if point.latencyMs is None else point.latencyMs
            self._alg[i] = code
            self._run[i] = run_id
            self._gap[i] = point.gap
            self._next = (i + 1) % self._num.shape[1] if self._num.shape[1] == self._max else i + 1
            if self._size < self._num.shape[1]:
                self._size += 1
            self.total_recorded += 1
            self._version += 1
        return True

    # -- reading ---------------------------------------------------------------
    def __len__(self) -> int:
        return self._size

    def column(self, name: str, last: int | None = None) -> np.ndarray:
        """A copy of one numeric column, oldest first (optionally only the ``last`` points)."""
        with self._lock:
            idx = _last(self._size, self._max, self._next, last or None)
            return np.array(self._num[_COL[name], idx], copy=True)

    def tail(self, last: int) -> tuple[dict[str, np.ndarray], np.ndarray, list[str]]:
        """The newest ``last`` points as columns (copies), their algorithm codes and the code names:
        what the plots draw, at a cost that depends on ``last``, not on the ring's size."""
        with self._lock:
            idx = _last(self._size, self._max, self._next, last)
            cols = {name: np.array(self._num[i, idx], copy=True) for name, i in _COL.items()}
            return cols, np.array(self._alg[idx], copy=True), list(self._algos)

    def algorithms(self) -> list[str]:
        """Algorithm of each stored point, oldest first."""
        with self._lock:
            codes = self._alg[_order(self._size, self._max, self._next)].copy()
            names = list(self._algos)
        return [names[c] for c in codes]

    def points(self) -> list[DataPoint]:
        """Every point the ring holds, oldest first."""
        return self.points_since(0)[0]

    def points_since(self, total: int) -> tuple[list[DataPoint], int]:
        """The points recorded after the first ``total`` (those the ring still holds), oldest first, and
        how many have been recorded in all: a reader that keeps up (the journal) sees each point once."""
        with self._lock:
            order = _last(self._size, self._max, self._next, max(0, self.total_recorded - total))
            num = self._num[:, order].copy()
            codes = self._alg[order].copy()
            runs = self._run[order].copy()
            gaps = self._gap[order].copy()
            names = list(self._algos)
            recorded = self.total_recorded
        out = []
        for j in range(num.shape[1]):
            lat = float(num[8, j])
            out.append(
                DataPoint(
                    float(num[0, j]),
                    float(num[1, j]),
                    float(num[2, j]),
                    float(num[3, j]),
                    float(num[4, j]),
                    float(num[5, j]),
                    float(num[6, j]),
                    float(num[7, j]),
                    names[codes[j]],
                    None if math.isnan(lat) else lat,
                    int(runs[j]) or None,
                    bool(gaps[j]),
                )
            )
        return out, recorded

    def stats(self) -> AnalyticsStats:
        """AnalyticsStats over every stored point, without copying the buffer."""
        with self._lock:
            n = self._size
            if n == 0:
                return EMPTY_STATS
            num = self._num[:, :n]
            x, y, gap = num[1], num[2], self._gap[:n]
            path = S.path_length(x, y, gap)
            if _wrapped(self._size, self._max, self._next):
                # Storage order wraps: the pair (newest, oldest) is not a real step, and the pair (last
                # slot, first slot) is, unless the sample in slot 0 follows a gap (path_length dropped the
                # step into a gap sample: here, the one into slot h is not counted either way)
                h = self._next
                if not gap[h]:
                    path -= math.hypot(x[h] - x[h - 1], y[h] - y[h - 1])
                if not gap[0]:
                    path += math.hypot(x[0] - x[-1], y[0] - y[-1])
            return compute_stats(x, y, num[4], num[5], num[6], num[7], path=max(path, 0.0))

    def stats_by_algorithm(self) -> dict[str, AnalyticsStats]:
        """AnalyticsStats per algorithm over the ring, in first-seen order; path length counts only steps
        between two consecutive samples of the same algorithm and the same run (``grouped_stats``)."""
        with self._lock:
            order = _order(self._size, self._max, self._next)
            num = self._num[:, order]
            codes = self._alg[order]
            runs = self._run[order]
            gaps = self._gap[order]
            names = list(self._algos)
        cols = {name: num[i] for name, i in _COL.items()}
        return grouped_stats(cols, [names[c] for c in codes.tolist()], runs, gaps)

    def nbytes(self) -> int:
        """Bytes held by the buffer arrays."""
        return int(self._num.nbytes + self._alg.nbytes + self._run.nbytes + self._gap.nbytes)


__all__ = [  # the data model lives in model.py; these names are read from here too
    "EMPTY_STATS", "FIELDS", "MAX_ALGORITHM_NAME", "MAX_CAPACITY", "NUMERIC", "STATS_FIELDS",
    "AnalyticsStats", "AnalyticsStore", "DataPoint", "compute_stats", "stats_of_points",
]  # fmt: skip


def runs_copy(store: AnalyticsStore) -> RunLog:
    """``store``'s runs as they are, copied under its lock (a running run's samples: 0.7 ms for an hour's
    at 10 Hz) for summaries computed outside it (``RunLog.summaries``, ``RunLog.by_algorithm``): what a
    thread off the command path reads, so a record never waits for a summary. (A function beside the
    class: the store has all the methods a class may.)"""
    with store._lock:
        return store._runs.snapshot()


def paths_in_force(store: AnalyticsStore) -> list[tuple[int, np.ndarray]]:
    """Each run's reference path in force now (the array itself, never written again: a replan replaces
    it), read under ``store``'s lock: what the journal writes as the runs' plans when one changed."""
    with store._lock:
        return [(r.id, r.path) for r in store._runs._runs if r.path is not None]
