"""Which controller is best: ranked within each mission, and overall only where the comparison is fair.

Pure (no I/O, no Textual). One definition used by the analytics screen, ``arbiter-tui compare`` and
``arbiter-tui stats``:

* **Within a mission** (like with like): completed entries first, then the lowest mean cross-track
  error to the mission's path (avg e_xt, ``tracking``); an entry without one (an export from before
  it was measured) by its mean distance error (avg e_d), after those with one. The seed's e_d is the
  distance to the *current waypoint*, so it mostly measures how far apart the waypoints are; e_xt
  measures how well the robot follows the path. An error measured on a square says nothing about one
  measured on a figure-eight, so entries of different missions are never ranked against each other.
* **Overall**: only over the missions that *every* ranked algorithm completed. On each of them an
  algorithm's place is its rank there; the overall best has the lowest mean rank (ties: more wins, then
  the first seen). An algorithm that never ran a mission is listed as "not run" there instead of
  competing, and that mission does not count towards the overall answer.

Manual driving is not a controller: it is never ranked.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol, TypeVar

from arbiter_core.controllers import MANUAL

from .model import AnalyticsStats
from .tracking import TrackingStats

RULE_MISSION = "per mission: completed first, then lowest mean cross-track error to the path (avg e_xt)"
RULE_OVERALL = (
    "overall: lowest mean rank over the missions every ranked algorithm completed (ties: more wins)"
)
RULE = f"{RULE_MISSION}; {RULE_OVERALL}"


class Entry(Protocol):
    """A run, or one algorithm's runs on one mission pooled."""

    @property
    def algorithm(self) -> str: ...

    @property
    def mission(self) -> str: ...

    @property
    def completed(self) -> bool | int: ...

    @property
    def stats(self) -> AnalyticsStats: ...

    @property
    def tracking(self) -> TrackingStats | None: ...


E = TypeVar("E", bound=Entry)


def rank_key(e: Entry) -> tuple[bool, bool, float]:
    """Within one mission: completed first, then by mean cross-track error (entries without one last,
    by mean distance error)."""
    t = e.tracking
    return (not e.completed, t is None, e.stats.avgDistanceError if t is None else t.xte_mean_m)


def ranked(entries: Iterable[E]) -> list[E]:
    return sorted(entries, key=rank_key)


def by_mission(entries: Iterable[E]) -> dict[str, list[E]]:
    """Entries grouped by mission (first-seen order), each group in rank order; manual driving left out."""
    groups: dict[str, list[E]] = {}
    for e in entries:
        if e.algorithm != MANUAL:
            groups.setdefault(e.mission, []).append(e)
    return {m: ranked(g) for m, g in groups.items()}


def best_in(group: Sequence[E]) -> E | None:
    """The best of one mission's (ranked) entries: the first, if it completed."""
    return group[0] if group and group[0].completed else None


@dataclass(frozen=True, slots=True)
class MissionRanking:
    mission: str
    algorithms: tuple[str, ...]  # in rank order (an algorithm's best entry decides its place)
    completed: tuple[str, ...]  # the algorithms that completed it at least once
    not_run: tuple[str, ...]  # ranked elsewhere, never ran this mission

    @property
    def best(self) -> str | None:
        return self.algorithms[0] if self.algorithms and self.algorithms[0] in self.completed else None


@dataclass(frozen=True, slots=True)
class Overall:
    best: str | None
    missions: tuple[str, ...]  # the missions the overall answer is over
    mean_rank: tuple[tuple[str, float], ...]  # (algorithm, mean rank) over those missions, best first
    wins: tuple[tuple[str, int], ...]
    tied: tuple[str, ...]  # when several share the lowest mean rank and wins: no single best
    reason: str  # the answer in words (why there is none, or what it is over)

    def as_dict(self) -> dict[str, object]:
        return {
            "best": self.best,
            "tied": list(self.tied),
            "missions": list(self.missions),
            "mean_rank": dict(self.mean_rank),
            "wins": dict(self.wins),
            "rule": RULE_OVERALL,
            "reason": self.reason,
        }


@dataclass(frozen=True, slots=True)
class Ranking:
    missions: tuple[MissionRanking, ...]
    overall: Overall


def rank(entries: Iterable[Entry]) -> Ranking:
    """Per-mission rankings and the overall answer (see the module's docstring for the rule)."""
    groups = by_mission(entries)
    algorithms = tuple(dict.fromkeys(e.algorithm for g in groups.values() for e in g))
    missions = []
    for mission, group in groups.items():
        order = tuple(dict.fromkeys(e.algorithm for e in group))
        done = tuple(dict.fromkeys(e.algorithm for e in group if e.completed))
        missions.append(MissionRanking(mission, order, done, tuple(a for a in algorithms if a not in order)))
    fair = tuple(m for m in missions if algorithms and set(m.completed) == set(algorithms))
    if not fair:
        if not algorithms:
            reason = "no controller has run yet"
        elif not any(m.completed for m in missions):
            reason = "no run completed yet"
        else:
            done_where = "; ".join(
                f"{a}: {', '.join(m.mission for m in missions if a in m.completed) or 'none'}"
                for a in algorithms
            )
            reason = f"no mission completed by every algorithm ({done_where})"
        return Ranking(tuple(missions), Overall(None, (), (), (), (), reason))
    ranks = {a: [m.algorithms.index(a) + 1 for m in fair] for a in algorithms}
    mean = {a: sum(r) / len(r) for a, r in ranks.items()}
    wins = {a: sum(1 for m in fair if m.best == a) for a in algorithms}
    standing = sorted(algorithms, key=lambda a: (mean[a], -wins[a]))
    top = standing[0]
    tied = tuple(a for a in standing if (mean[a], wins[a]) == (mean[top], wins[top]))
    over = ", ".join(m.mission for m in fair)
    if len(tied) > 1:
        best = None
        reason = f"no single best: {', '.join(tied)} tie (mean rank {mean[top]:g} over {over})"
    else:
        best = top
        reason = f"{top} (mean rank {mean[top]:g} over {over})"
    return Ranking(
        tuple(missions),
        Overall(
            best,
            tuple(m.mission for m in fair),
            tuple((a, round(mean[a], 4)) for a in standing),
            tuple((a, wins[a]) for a in standing),
            tied if best is None else (),
            reason,
        ),
    )
