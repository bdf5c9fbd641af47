"""The comparison as a table: columns with units, rows grouped by mission, the best value per column
and mission marked, the best of each mission and overall named by one rule (``ranking.py``), sortable
within each mission. Pure (no Textual): the analytics screen shows it, tests read it.

Marks are characters, not colour alone: ``◆`` after the best value of a column where lower is better
(within a mission, among rows with a completed run), ``★`` before the best of each mission.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from . import ranking
from .labels import format_stat
from .runs import LOWER_IS_BETTER, AlgorithmSummary, RunSummary, best_in_columns

BEST_CELL = "◆"
BEST_ROW = "★"
BY_ALGORITHM = "algorithm"
BY_RUN = "run"
RANK = "rank"  # the default order: the rule's

Row = RunSummary | AlgorithmSummary


@dataclass(frozen=True, slots=True)
class Column:
    key: str  # a RunSummary/AlgorithmSummary attribute, or an AnalyticsStats field
    header: str  # with its unit
    text: Callable[[Row], str]


def _stat(name: str) -> Callable[[Row], str]:
    return lambda r: format_stat(name, getattr(r.stats, name), decimals=3, unit=False)


def _opt(attr: str, fmt: str) -> Callable[[Row], str]:
    def text(r: Row) -> str:
        value = getattr(r, attr)
        return "—" if value is None else format(value, fmt)

    return text


_AVG = Column("avgDistanceError", "avg e_d m", _stat("avgDistanceError"))
_STD = Column("stdDevError", "std e_d m", _stat("stdDevError"))
_TAIL = (
    Column("p95Error", "p95 e_d m", _stat("p95Error")),
    Column("avgHeadingError", "|e_θ| rad", _stat("avgHeadingError")),
    Column("totalPathLength", "path m", lambda r: f"{r.stats.totalPathLength:.2f}"),
    Column("sampleCount", "samples", lambda r: str(r.stats.sampleCount)),
)
_MISSION = Column("mission", "mission", lambda r: r.mission or "—")
ALGORITHM_COLUMNS = (
    _MISSION,
    Column("algorithm", "algorithm", lambda r: r.algorithm),
    Column("completed", "done", lambda r: f"{int(r.completed)}/{getattr(r, 'runs', 1)}"),
    Column("time_s", "time s", _opt("time_s", ".1f")),
    Column("final_error_m", "final m", _opt("final_error_m", ".3f")),
    _AVG,
    _STD,
    *_TAIL,
)
RUN_COLUMNS = (
    Column("id", "run", lambda r: str(getattr(r, "id", ""))),
    Column("algorithm", "algorithm", lambda r: r.algorithm),
    _MISSION,
    Column("outcome", "outcome", lambda r: getattr(r, "outcome", "")),
    Column("time_s", "time s", _opt("time_s", ".1f")),
    Column("final_error_m", "final m", _opt("final_error_m", ".3f")),
    _AVG,
    *_TAIL,
)  # std e_d left out: a run row is wide already (stats --by run prints all nine)
SORTABLE = {c.key for c in RUN_COLUMNS + ALGORITHM_COLUMNS}


@dataclass(frozen=True, slots=True)
class Table:
    headers: tuple[str, ...]
    keys: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    best: str | None  # the best overall by ranking.RULE_OVERALL, or None (then ``overall`` says why)
    overall: str  # the overall answer in words
    rule: str


def sort_value(row: Row, key: str) -> tuple[bool, float | str]:
    """Missing values last; text columns alphabetically."""
    if key == RANK:
        return ranking.rank_key(row)
    if hasattr(row.stats, key):
        return (False, float(getattr(row.stats, key)))
    value = getattr(row, key, None)
    if value is None:
        return (True, 0.0)
    if isinstance(value, bool):
        return (False, float(not value))  # completed first
    return (False, value)


def build(
    mode: str,
    runs: Sequence[RunSummary],
    algorithms: Sequence[AlgorithmSummary],
    sort: str = RANK,
    descending: bool = False,
) -> Table:
    """Rows grouped by mission (in the order missions were first driven; manual driving last), sorted
    within each mission; ``★`` on each mission's best, the overall best by ``ranking.RULE_OVERALL``."""
    columns = ALGORITHM_COLUMNS if mode == BY_ALGORITHM else RUN_COLUMNS
    source: list[Row] = list(algorithms if mode == BY_ALGORITHM else runs)
    groups: dict[tuple[bool, str], list[Row]] = {}
    for item in source:
        groups.setdefault((item.algorithm == ranking.MANUAL, item.mission), []).append(item)
    items: list[Row] = []
    for key in sorted(groups, key=lambda k: k[0]):  # stable: first-seen order, manual last
        items.extend(sorted(groups[key], key=lambda r: sort_value(r, sort), reverse=descending))
    tops = {id(b) for g in ranking.by_mission(items).values() if (b := ranking.best_in(g)) is not None}
    marks = best_in_columns(items, LOWER_IS_BETTER)
    rows = []
    for i, item in enumerate(items):
        cells = []
        for c in columns:
            text = c.text(item)
            if i in marks.get(c.key, ()):
                text = f"{text} {BEST_CELL}"
            cells.append(text)
        if id(item) in tops:  # on the algorithm, the second column in both views
            cells[1] = f"{BEST_ROW} {cells[1]}"
        rows.append(tuple(cells))
    overall = ranking.rank(algorithms if algorithms else runs).overall
    return Table(
        headers=tuple(c.header for c in columns),
        keys=tuple(c.key for c in columns),
        rows=tuple(rows),
        best=overall.best,
        overall=overall.reason,
        rule=ranking.RULE_MISSION,
    )


def legend(table: Table) -> str:
    """The rule in one line, as the screen shows it under the table."""
    return (
        f"{BEST_ROW} best of its mission ({table.rule.removeprefix('per mission: ')}) · overall: "
        f"{table.overall} · {BEST_CELL} best of its column in its mission"
    )
