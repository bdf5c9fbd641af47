"""Runs: what the comparison compares. Pure: numpy and the store's formulas, no I/O, no Textual.

A run is one mission run (``g`` → completed / aborted / overridden) or one stretch of manual driving
(first key press → 2 s without a movement key). Its samples are the DataPoints recorded while it was
active; a sample recorded outside every run (the robot standing still, a manual pause) belongs to none,
so it counts in the seed's whole-buffer AnalyticsStats but in no run's.

A run keeps its own copy of the six columns the statistics need (48 bytes a sample), so its nine
AnalyticsStats are the seed's formulas (``compute_stats``) over *all* of its samples, however small the
ring buffer is: a run of 392 samples says 392 after the ring has dropped half of them, and says how many
the ring still holds (``in_ring``).
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from arbiter_core import stats as S
from arbiter_core.controllers import MANUAL

from . import tracking as T
from .model import EMPTY_STATS, AnalyticsStats, compute_stats
from .tracking import TrackingStats

RUNNING = "running"
COMPLETED = "completed"
ABORTED = "aborted"  # stopped: space/k, a screen too small, the link lost, another algorithm or mission
OVERRIDDEN = "overridden"  # a movement key took over from the controller
ENDED = "ended"  # a manual run: 2 s without a movement key
OUTCOMES = (RUNNING, COMPLETED, ABORTED, OVERRIDDEN, ENDED)
MANUAL_IDLE_S = 2.0
STILL_V = 0.005  # m/s: odometry slower than this (and STILL_W) with no command is a robot standing still
STILL_W = 0.01  # rad/s

# Columns where lower is better and a "best" mark means something; the others (samples, speeds, path)
# have no better direction and are never marked.
LOWER_IS_BETTER = (
    "time_s", "final_error_m", "xte_mean_m", "xte_p95_m", "avgDistanceError", "stdDevError", "p95Error",
    "avgHeadingError", "mean_abs_dw_dt",
)  # fmt: skip


class IdleSamples:
    """Whether a sample is taken, for a robot standing still outside every run (no run, no command,
    odometry below ``STILL_V``/``STILL_W``): the first, where it stopped, and then none until it moves,
    so idle time never pushes run samples out of the ring buffer nor dilutes the whole-buffer figures.
    One rule for every way of sampling: the console's control loop and observe mode (live or a bag)."""

    __slots__ = ("_taken",)

    def __init__(self) -> None:
        self._taken = False  # the standing robot's one sample was taken

    def wanted(self, in_run: bool, commanding: bool, v: float, w: float) -> bool:
        """A sample now? ``commanding``: a nonzero command is in force; ``v``, ``w``: the odometry's."""
        still = not in_run and not commanding and abs(v) < STILL_V and abs(w) < STILL_W
        if still and self._taken:
            return False
        self._taken = still
        return True


@dataclass(frozen=True, slots=True)
class RunSummary:
    """One run as the comparison shows it; frozen, so a view can hold it."""

    id: int
    algorithm: str
    mission: str  # "" for manual driving
    start_ms: float
    end_ms: float | None  # None while running
    outcome: str
    final_error_m: float | None  # distance to the mission's last waypoint when it ended; None for manual
    stats: AnalyticsStats
    in_ring: int  # how many of its samples the ring buffer still holds
    last_ms: float | None = None  # timestamp of its last sample
    tracking: TrackingStats | None = None  # against its reference path (``tracking``); None for manual

    @property
    def completed(self) -> bool:
        return self.outcome == COMPLETED

    @property
    def time_s(self) -> float:
        """From its start to its end (or to its last sample while it runs)."""
        end = self.end_ms if self.end_ms is not None else (self.last_ms or self.start_ms)
        return max(0.0, (end - self.start_ms) / 1000.0)

    def rounded(self) -> tuple[float, float | None]:
        """Its time and final error as the exports write them (to the millisecond, to 0.1 mm)."""
        final = None if self.final_error_m is None else round(self.final_error_m, 4)
        return round(self.time_s, 3), final

    @property
    def dropped(self) -> int:
        """Samples of this run the ring buffer no longer holds (its summary still counts them)."""
        return self.stats.sampleCount - self.in_ring

    def as_dict(self) -> dict[str, Any]:
        time_s, final = self.rounded()
        return {
            "id": self.id,
            "algorithm": self.algorithm,
            "mission": self.mission,
            "outcome": self.outcome,
            "completed": self.completed,
            "start_ms": self.start_ms,
            "end_ms": self.end_ms,
            "time_s": time_s,
            "final_error_m": final,
            "stats": self.stats.as_dict(),
            "tracking": None if self.tracking is None else self.tracking.as_dict(),
        }


@dataclass(frozen=True, slots=True)
class AlgorithmSummary:
    """Every run of one algorithm on one mission together: its samples pooled, its completed runs
    averaged. Runs of different missions are never pooled (their distance errors do not compare)."""

    algorithm: str
    mission: str  # "" for manual driving
    runs: int
    completed: int
    time_s: float | None  # mean over completed runs
    final_error_m: float | None  # mean over completed runs
    stats: AnalyticsStats  # over the pooled samples of all its runs; path = sum of the runs' paths
    tracking: TrackingStats | None = None  # ``tracking.pooled`` over its runs; None for manual

    def as_dict(self) -> dict[str, Any]:
        return {
            "algorithm": self.algorithm,
            "mission": self.mission,
            "runs": self.runs,
            "completed": self.completed,
            "time_s": None if self.time_s is None else round(self.time_s, 3),
            "final_error_m": None if self.final_error_m is None else round(self.final_error_m, 4),
            "stats": self.stats.as_dict(),
            "tracking": None if self.tracking is None else self.tracking.as_dict(),
        }


def column_value(row: RunSummary | AlgorithmSummary, column: str) -> float | None:
    if column in ("time_s", "final_error_m"):
        value = getattr(row, column)
        return None if value is None else float(value)
    if column in T.TRACKING_FIELDS:
        value = None if row.tracking is None else getattr(row.tracking, column)
        return None if value is None else float(value)
    return float(getattr(row.stats, column))


def best_in_columns(
    rows: Sequence[RunSummary | AlgorithmSummary], columns: Iterable[str] = LOWER_IS_BETTER
) -> dict[str, set[int]]:
    """Indices of the best row per column within each mission (one per mission and column), among rows
    with a completed run (ties: the first). Manual driving is never marked."""
    out: dict[str, set[int]] = {}
    for column in columns:
        best: dict[str, tuple[float, int]] = {}
        for i, r in enumerate(rows):
            if not r.completed or r.algorithm == MANUAL:
                continue
            v = column_value(r, column)
            if v is not None and (r.mission not in best or (v, i) < best[r.mission]):
                best[r.mission] = (v, i)
        if best:
            out[column] = {i for _v, i in best.values()}
    return out


class _Run:
    __slots__ = ("_index", "_summary", "algorithm", "cols", "end_ms", "final_error_m", "first", "id",
                 "in_ring", "last_ms", "measured", "mission", "n", "outcome", "path", "stand_in",
                 "start_ms", "unseen_m")  # fmt: skip

    def __init__(
        self,
        run_id: int,
        algorithm: str,
        mission: str,
        start_ms: float,
        path: np.ndarray | None = None,
        stand_in: bool = False,
    ) -> None:
        self.id = run_id
        self.algorithm = algorithm
        self.mission = mission
        self.start_ms = start_ms
        self.end_ms: float | None = None
        self.outcome = RUNNING
        self.final_error_m: float | None = None
        # The reference path in force (``tracking.reference_path``, or the plan a robot's controller
        # follows): each sample's cross-track error is taken against the one in force when it came.
        # None: no tracking metrics (manual driving).
        self.path = path
        self._index: T.PathIndex | None = None  # the path in force, indexed once it is measured against
        # The run's first reference, what its path ratio and time limit are against; a stand-in (an
        # observed goal's straight line) gives way to the first plan that comes.
        self.first = path
        self.stand_in = stand_in
        self.cols = np.empty((8, 64), dtype=np.float64)  # x, y, v, w, e_d, e_th, t (ms), cross-track
        self.n = 0
        self.measured = 0  # samples whose cross-track error is in cols[7]
        self.in_ring = 0
        self.last_ms: float | None = None
        self.unseen_m = 0.0  # steps into samples that follow a gap: not part of its path length
        self._summary: RunSummary | None = None

    def add(
        self, t_ms: float, x: float, y: float, v: float, w: float, e_d: float, e_th: float, gap: bool = False
    ) -> None:
        if gap and self.n:
            self.unseen_m += float(np.hypot(x - self.cols[0, self.n - 1], y - self.cols[1, self.n - 1]))
        if self.n == self.cols.shape[1]:
            grown = np.empty((8, self.n * 2), dtype=np.float64)
            grown[:, : self.n] = self.cols
            self.cols = grown
        self.cols[:7, self.n] = (x, y, v, w, e_d, e_th, t_ms)
        self.n += 1
        self.in_ring += 1
        self.last_ms = t_ms
        self._summary = None

    def follow(self, path: np.ndarray) -> None:
        """From the next sample on, measure against ``path`` (a replan); the first plan replaces a
        stand-in as the run's first reference."""
        self._measure()
        self.path = path
        self._index = None
        if self.stand_in or self.first is None:
            self.first, self.stand_in = path, False
        self._summary = None

    def drop_after(self, t_ms: float) -> int:
        """Forget the samples taken after ``t_ms`` (the run ended before them); how many."""
        keep = int(np.searchsorted(self.cols[6, : self.n], t_ms, side="right"))
        dropped = self.n - keep
        if dropped:
            self.n = keep
            self.measured = min(self.measured, keep)
            self.in_ring = max(0, self.in_ring - dropped)
            self.last_ms = float(self.cols[6, keep - 1]) if keep else None
            self._summary = None
        return dropped

    def _measure(self) -> None:
        """The cross-track errors of the samples taken since the last measure, against the path in force."""
        if self.path is None or self.measured == self.n:
            return
        if self._index is None:
            self._index = T.PathIndex(self.path)
        c = self.cols
        lo, hi = self.measured, self.n
        c[7, lo:hi] = self._index.distances(c[0, lo:hi], c[1, lo:hi])
        self.measured = hi

    def summary(self) -> RunSummary:
        if self._summary is None:
            c = self.cols[:, : self.n]
            stats = EMPTY_STATS
            if self.n:
                path = max(0.0, S.path_length(c[0], c[1]) - self.unseen_m) if self.unseen_m else None
                stats = compute_stats(c[0], c[1], c[2], c[3], c[4], c[5], path=path)
            summary = RunSummary(
                self.id, self.algorithm, self.mission, self.start_ms, self.end_ms, self.outcome,
                self.final_error_m, stats, self.in_ring, self.last_ms,
            )  # fmt: skip
            if self.first is not None and self.n:
                done = summary.time_s if self.outcome == COMPLETED else None
                tracking = T.tracking_of(
                    c[6] / 1e3, c[2], c[3], self.cross_track(), T.path_length(self.first),
                    stats.totalPathLength, done,
                )  # fmt: skip
                summary = replace(summary, tracking=tracking)
            self._summary = summary
        return self._summary

    def snapshot(self, active: bool) -> _Run:
        """This run as it is now, to summarize outside the store's lock: its samples copied where a
        summary will read them (none cached) or the run may still change them (``active``); a finished
        run's samples are shared (never written again: its pooled row reads them)."""
        out = copy.copy(self)
        if active or self._summary is None:
            out.cols = self.cols[:, : self.n].copy()
        return out

    def cross_track(self) -> np.ndarray:
        """Each sample's cross-track error against the reference in force when it was taken."""
        self._measure()
        return self.cols[7, : self.n] if self.first is not None else self.cols[7, :0]


class RunLog:
    """Every run of the session, in order. Not thread-safe on its own: the store calls it under its lock."""

    def __init__(self) -> None:
        self._runs: list[_Run] = []
        self._by_id: dict[int, _Run] = {}
        self._active: _Run | None = None
        self._next_id = 1
        self._pooled: dict[tuple[str, str], tuple[tuple[tuple[int, int, str], ...], AlgorithmSummary]] = {}

    @property
    def active(self) -> int | None:
        return None if self._active is None else self._active.id

    def active_algorithm(self) -> str | None:
        return None if self._active is None else self._active.algorithm

    def begin(
        self,
        algorithm: str,
        mission: str,
        t_ms: float,
        path: np.ndarray | None = None,
        stand_in: bool = False,
    ) -> int:
        """Start a run (ending the active one as aborted); returns its id. ``path``: the reference path
        its tracking metrics are measured against (none for manual driving); ``stand_in``: it stands in
        until a plan comes (:meth:`follow`), and the plan, not it, is the run's first reference."""
        if self._active is not None:
            self.end(ABORTED, t_ms)
        run = _Run(self._next_id, algorithm, mission, t_ms, path, stand_in)
        self._next_id += 1
        self._runs.append(run)
        self._by_id[run.id] = run
        self._active = run
        return run.id

    def follow(self, path: np.ndarray) -> None:
        """The active run's samples from now on are measured against ``path`` (an observed robot's plan,
        which comes a moment after its goal, and every replan after it)."""
        if self._active is not None:
            self._active.follow(path)

    def drop_after(self, t_ms: float) -> int:
        """The active run's samples after ``t_ms`` leave it (it ended before them); how many."""
        return 0 if self._active is None else self._active.drop_after(t_ms)

    def end(self, outcome: str, t_ms: float, final_error_m: float | None = None) -> RunSummary | None:
        """End the active run; returns its summary (None when no run was active)."""
        if outcome not in OUTCOMES or outcome == RUNNING:
            raise ValueError(f"a run ends as one of {', '.join(OUTCOMES[1:])}, not {outcome!r}")
        run = self._active
        if run is None:
            return None
        self._active = None
        if run.n == 0:
            # A run that recorded nothing (collection paused) is forgotten, and so is its number: the
            # numbers a user sees are 1, 2, 3... with every numbered run listed.
            self._runs.remove(run)
            del self._by_id[run.id]
            self._next_id = run.id
            return None
        run.end_ms = max(t_ms, run.start_ms)
        run.outcome = outcome
        run.final_error_m = final_error_m
        run._summary = None
        return run.summary()

    def add(self, run_id: int, t_ms: float, x: float, y: float, v: float, w: float, e_d: float,
            e_th: float, gap: bool = False) -> bool:  # fmt: skip
        """A sample of the active run; False (and nothing kept) for any other id."""
        run = self._active
        if run is None or run.id != run_id:
            return False
        run.add(t_ms, x, y, v, w, e_d, e_th, gap)
        return True

    def evicted(self, run_id: int, count: int = 1) -> None:
        """The ring buffer dropped ``count`` samples of this run (its summary keeps them)."""
        run = self._by_id.get(run_id)
        if run is not None and run.in_ring > 0:
            run.in_ring = max(0, run.in_ring - count)
            run._summary = None

    def snapshot(self) -> RunLog:
        """The runs as they are now, for summaries and rows computed outside the store's lock (the
        store copies under its lock, the journal computes on its own thread: ``store.runs_copy``)."""
        out = RunLog()
        out._runs = [r.snapshot(r is self._active) for r in self._runs]
        out._by_id = {r.id: r for r in out._runs}
        out._next_id = self._next_id
        out._pooled = dict(self._pooled)
        return out

    def summaries(self, with_samples_only: bool = True) -> tuple[RunSummary, ...]:
        return tuple(r.summary() for r in self._runs if r.n or not with_samples_only)

    def get(self, run_id: int) -> RunSummary | None:
        run = self._by_id.get(run_id)
        return None if run is None else run.summary()

    def by_algorithm(self) -> tuple[AlgorithmSummary, ...]:
        """One row per (mission, algorithm) with samples, in first-run order; recomputed only for a row
        whose runs changed (a finished row costs nothing while another one drives)."""
        groups: dict[tuple[str, str], list[_Run]] = {}
        for r in self._runs:
            if r.n:
                groups.setdefault((r.mission, r.algorithm), []).append(r)
        out = []
        for (mission, algorithm), runs in groups.items():
            key = tuple((r.id, r.n, r.outcome) for r in runs)
            cached = self._pooled.get((mission, algorithm))
            if cached is None or cached[0] != key:
                cached = (key, _pool(algorithm, mission, runs))
                self._pooled[(mission, algorithm)] = cached
            out.append(cached[1])
        return tuple(out)

    def clear(self) -> None:
        """Forget every run and start numbering again at 1; an active run goes on from now, as run 1."""
        active = self._active
        self._runs.clear()
        self._by_id.clear()
        self._pooled.clear()
        self._active = None
        self._next_id = 1
        if active is not None:
            self.begin(active.algorithm, active.mission, active.start_ms, active.path, active.stand_in)


def row_of(run: RunSummary) -> AlgorithmSummary:
    """The per-(mission, algorithm) row of a mission driven once (as ``arbiter-tui compare`` drives)."""
    done = run.completed
    return AlgorithmSummary(
        algorithm=run.algorithm,
        mission=run.mission,
        runs=1,
        completed=int(done),
        time_s=run.time_s if done else None,
        final_error_m=run.final_error_m if done else None,
        stats=run.stats,
        tracking=run.tracking,
    )


def _pool(algorithm: str, mission: str, runs: list[_Run]) -> AlgorithmSummary:
    # x and y only make the path, which is the sum of the runs' paths (no step between two runs)
    cols = np.concatenate([r.cols[2:6, : r.n] for r in runs], axis=1)
    path = sum(r.summary().stats.totalPathLength for r in runs)
    none = cols[0][:0]
    stats = compute_stats(none, none, cols[0], cols[1], cols[2], cols[3], path=path)
    done = [r.summary() for r in runs if r.outcome == COMPLETED]
    errors = [s.final_error_m for s in done if s.final_error_m is not None]
    tracked = [(r.cross_track(), t, r.n) for r in runs if (t := r.summary().tracking) is not None]
    return AlgorithmSummary(
        algorithm=algorithm,
        mission=mission,
        runs=len(runs),
        completed=len(done),
        time_s=sum(s.time_s for s in done) / len(done) if done else None,
        final_error_m=sum(errors) / len(errors) if errors else None,
        stats=stats,
        tracking=T.pooled(tracked),
    )
