"""Trials of one comparison cell (a controller on a mission behind one link), summed up with their
uncertainty, and the verdict on which controller is best. Pure: no I/O, no Textual.

Each cell is run ``trials`` times with the link's jitter and loss drawn from a different seed. A figure
is reported as the mean over the trials ± the half-width of its 95 % interval (Student's t,
``arbiter_core.stats.mean_ci95``). Within a mission the entries are ranked by the product's rule
(``analytics.ranking``: completed in every trial first, then the lowest mean cross-track error); the
best is a **clear winner** only when its interval does not overlap the runner-up's, otherwise the
mission's verdict is "no clear winner" and names the entries whose intervals overlap the best's.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any

from arbiter_core.stats import mean_ci95

from ..analytics import ranking
from ..analytics import tracking as T
from ..analytics.model import AnalyticsStats
from ..analytics.tracking import TrackingStats
from .compare import RunResult

INTERVAL = "mean over trials ± half-width of its 95 % t-interval"
VERDICT_RULE = "a clear winner only when its interval does not overlap the runner-up's"
FIGURES = (
    "xte_mean_m", "xte_p95_m", "xte_max_m", "time_s", "path_ratio", "mean_abs_dw_dt", "avgDistanceError",
)  # fmt: skip


@dataclass(frozen=True, slots=True)
class Figure:
    mean: float
    ci95: float  # half-width

    @property
    def low(self) -> float:
        return self.mean - self.ci95

    @property
    def high(self) -> float:
        return self.mean + self.ci95

    def text(self, digits: int = 3, interval: bool | None = None) -> str:
        """``mean±ci95`` to ``digits`` decimals (``—`` for no value). ``interval``: True or False gives
        every cell of a table's column the same form (a table passes whether it holds several trials);
        None shows the interval only when it has width (the verdict's ``reason`` in ``--json``)."""
        if not math.isfinite(self.mean):
            return "—"
        mean = f"{self.mean:.{digits}f}"
        if interval is None:
            interval = self.ci95 != 0
        return f"{mean}±{self.ci95:.{digits}f}" if interval else mean

    def shown(self, digits: int) -> Figure:
        """The figure as a reader sees it printed to ``digits`` decimals."""
        return Figure(float(f"{self.mean:.{digits}f}"), float(f"{self.ci95:.{digits}f}"))

    def as_dict(self) -> dict[str, float]:
        return {"mean": round(self.mean, 6), "ci95": round(self.ci95, 6)}


@dataclass(frozen=True, slots=True)
class CellSummary:
    """One controller on one mission behind one link, over its trials (a ``ranking.Entry``)."""

    algorithm: str
    mission: str
    trials: int
    completions: int
    figures: dict[str, Figure]
    stats: AnalyticsStats  # each field the mean over the trials (ranking's fallback; shown as e_d)
    tracking: TrackingStats  # each field the mean over the trials (what the ranking reads)

    @property
    def completed(self) -> bool:
        """Completed in every trial (one failure is not a controller to recommend)."""
        return self.completions == self.trials

    def as_dict(self) -> dict[str, Any]:
        return {
            "algorithm": self.algorithm,
            "mission": self.mission,
            "trials": self.trials,
            "completed": self.completions,
            **{k: f.as_dict() for k, f in self.figures.items()},
        }


def _value(r: RunResult, name: str) -> float | None:
    if name == "time_s":
        return r.time_s if r.completed else None
    if name == "avgDistanceError":
        return r.stats.avgDistanceError
    value: float | None = getattr(r.tracking, name)
    return value


def summarize(runs: Sequence[RunResult]) -> CellSummary:
    """The trials of one cell (same algorithm and mission)."""
    first = runs[0]
    figures = {}
    for name in FIGURES:
        values = [v for r in runs if (v := _value(r, name)) is not None]
        figures[name] = Figure(*mean_ci95(values)) if values else Figure(float("nan"), 0.0)
    def stat_mean(name: str) -> float:
        total: float = sum(getattr(r.stats, name) for r in runs)
        return total / len(runs)

    stats = AnalyticsStats(
        round(stat_mean("sampleCount")),
        **{f.name: float(stat_mean(f.name)) for f in fields(AnalyticsStats) if f.name != "sampleCount"},
    )
    times = [r.time_s for r in runs if r.completed]
    ratios = [r.tracking.path_ratio for r in runs if r.tracking.path_ratio is not None]
    tracking = TrackingStats(
        samples=round(sum(r.tracking.samples for r in runs) / len(runs)),
        xte_mean_m=figures["xte_mean_m"].mean,
        xte_rms_m=sum(r.tracking.xte_rms_m for r in runs) / len(runs),
        xte_p95_m=figures["xte_p95_m"].mean,
        xte_max_m=figures["xte_max_m"].mean,
        time_to_complete_s=sum(times) / len(times) if times else None,
        path_ratio=sum(ratios) / len(ratios) if ratios else None,
        mean_abs_dw_dt=figures["mean_abs_dw_dt"].mean,
        linear_jerk=T.mean_of([r.tracking.linear_jerk for r in runs]),
        angular_jerk=T.mean_of([r.tracking.angular_jerk for r in runs]),
        success=T.mean_of([r.tracking.success for r in runs]),
    )
    return CellSummary(
        first.algorithm, first.mission, len(runs), sum(r.completed for r in runs), figures, stats, tracking
    )


def cells(trials: Sequence[Sequence[RunResult]]) -> list[CellSummary]:
    """``trials[k]`` is the k-th trial of one comparison (the same runs in the same order each time)."""
    return [summarize([t[i] for t in trials]) for i in range(len(trials[0]))]


@dataclass(frozen=True, slots=True)
class Verdict:
    mission: str
    ranking: tuple[CellSummary, ...]  # in rank order
    best: str | None  # a clear winner, or None
    overlapping: tuple[str, ...]  # with the best (empty when it is clear)
    reason: str  # as --json carries it (the figure to 3 decimals); the tables print text()

    def text(self, digits: int = 3, interval: bool | None = None) -> str:
        """The reason with its figure as the mission's table prints it."""
        return _reason(self.ranking[0], self.best, self.overlapping, digits, interval)

    def as_dict(self) -> dict[str, Any]:
        return {
            "mission": self.mission,
            "best": self.best,
            "clear": self.best is not None,
            "overlapping": list(self.overlapping),
            "reason": self.reason,
            "ranking": [{"rank": i, **c.as_dict()} for i, c in enumerate(self.ranking, 1)],
        }


def _reason(
    top: CellSummary, best: str | None, overlap: Sequence[str], digits: int = 3, interval: bool | None = None
) -> str:
    if not top.completed:
        return "no controller completed every trial"
    xte = top.figures["xte_mean_m"].text(digits, interval)
    if best is None:
        names = ", ".join((top.algorithm, *overlap))
        return f"no clear winner: {names} overlap (avg e_xt {xte} m for {top.algorithm})"
    return f"{top.algorithm} (avg e_xt {xte} m, apart from every other)"


def verdicts(summaries: Sequence[CellSummary]) -> list[Verdict]:
    """Per mission: the ranking, and a best only when its interval of mean cross-track error is apart from
    the runner-up's."""
    out = []
    for mission, group in ranking.by_mission(summaries).items():
        top = group[0]
        xte = top.figures["xte_mean_m"]
        best: str | None = None
        overlap: tuple[str, ...] = ()
        if top.completed:
            rivals = [c for c in group[1:] if c.completed]
            overlap = tuple(c.algorithm for c in rivals if _overlaps(c.figures["xte_mean_m"], xte))
            best = None if overlap else top.algorithm
        out.append(Verdict(mission, tuple(group), best, overlap, _reason(top, best, overlap)))
    return out


def _overlaps(rival: Figure, top: Figure) -> bool:
    return rival.low <= top.high


MORE_DIGITS = 3  # at most this many decimals beyond a column's usual ones (metres: down to the micrometre)


def decimals(ranked: Sequence[Figure], base: int = 3, verdict: Verdict | None = None) -> int:
    """The fewest decimals (at least ``base``, at most ``base + MORE_DIGITS``) at which a ranked column
    shows what the ranking and the verdict see: neighbours in rank order whose means differ print
    different means, and, given the mission's verdict (``ranked`` is then its avg e_xt column), each
    completed rival's printed interval overlaps the best's printed one exactly when the verdict says so."""
    rivals: list[tuple[Figure, bool]] = []
    if verdict is not None and verdict.ranking[0].completed:
        top = verdict.ranking[0].figures["xte_mean_m"]
        rivals = [
            (c.figures["xte_mean_m"], _overlaps(c.figures["xte_mean_m"], top))
            for c in verdict.ranking[1:]
            if c.completed
        ]

    def tells_apart(d: int) -> bool:
        for a, b in itertools.pairwise(ranked):
            finite = math.isfinite(a.mean) and math.isfinite(b.mean)
            if finite and a.mean != b.mean and f"{a.mean:.{d}f}" == f"{b.mean:.{d}f}":
                return False
        if verdict is None or not rivals:
            return True
        top_shown = verdict.ranking[0].figures["xte_mean_m"].shown(d)
        return all(_overlaps(f.shown(d), top_shown) == seen for f, seen in rivals)

    return next((d for d in range(base, base + MORE_DIGITS) if tells_apart(d)), base + MORE_DIGITS)
