"""The comparison as a table: columns with units, rows grouped by mission, the best value per column
and mission marked, the best of each mission and overall named by one rule (``ranking.py``), sortable
within each mission. Pure (no Textual): the analytics screen shows it, tests read it.

Marks are characters, not colour alone: ``◆`` after the best value of a column where lower is better
(within a mission, among rows with a completed run), ``★`` before the best of each mission.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from arbiter_core.controllers import MANUAL

from . import ranking
from .labels import format_stat
from .runs import LOWER_IS_BETTER, AlgorithmSummary, RunSummary, best_in_columns, column_value
from .tracking import TRACKING_FIELDS

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
    short: str = ""  # the compact view's header (units in the legend); "" = the same
    short_text: Callable[[Row], str] | None = None  # the compact view's cell, when shorter


def _stat(name: str) -> Callable[[Row], str]:
    return lambda r: format_stat(name, getattr(r.stats, name), decimals=3, unit=False)


def _opt(attr: str, fmt: str) -> Callable[[Row], str]:
    def text(r: Row) -> str:
        value = getattr(r, attr)
        return "—" if value is None else format(value, fmt)

    return text


SHORT_OUTCOME = {
    "completed": "done", "aborted": "abort", "overridden": "over", "ended": "end", "running": "run",
}  # fmt: skip
_AVG = Column("avgDistanceError", "avg e_d m", _stat("avgDistanceError"), "e_d")
_STD = Column("stdDevError", "std e_d m", _stat("stdDevError"), "std")
_TAIL = (
    Column("p95Error", "p95 e_d m", _stat("p95Error"), "p95"),
    Column("avgHeadingError", "|e_θ| rad", _stat("avgHeadingError"), "|e_θ|"),
    Column("totalPathLength", "path m", lambda r: f"{r.stats.totalPathLength:.2f}", "path"),
    Column("sampleCount", "samples", lambda r: str(r.stats.sampleCount), "n"),
)


def _track(attr: str, fmt: str) -> Callable[[Row], str]:
    def text(r: Row) -> str:
        value = column_value(r, attr)
        return "—" if value is None else format(value, fmt)

    return text


_XTE = Column("xte_mean_m", "avg e_xt m", _track("xte_mean_m", ".3f"), "e_xt")
_XTE95 = Column("xte_p95_m", "p95 e_xt m", _track("xte_p95_m", ".3f"), "p95xt")
_RATIO = Column("path_ratio", "path/ref", _track("path_ratio", ".2f"), "/ref")
_SMOOTH = Column("mean_abs_dw_dt", "|dω/dt| rad/s²", _track("mean_abs_dw_dt", ".2f"), "|ω'|")
_MISSION = Column("mission", "mission", lambda r: r.mission or "—")
_TIME = Column("time_s", "time s", _opt("time_s", ".1f"), "t")
_FINAL = Column("final_error_m", "final m", _opt("final_error_m", ".3f"), "final")
ALGORITHM_COLUMNS = (
    _MISSION,
    Column("algorithm", "algorithm", lambda r: r.algorithm),
    Column("completed", "done", lambda r: f"{int(r.completed)}/{getattr(r, 'runs', 1)}"),
    _TIME,
    _FINAL,
    _XTE,
    _XTE95,
    _RATIO,
    _SMOOTH,
    _AVG,
    _STD,
    *_TAIL,
)
RUN_COLUMNS = (
    Column("id", "run", lambda r: str(getattr(r, "id", ""))),
    Column("algorithm", "algorithm", lambda r: r.algorithm),
    _MISSION,
    Column(
        "outcome",
        "outcome",
        lambda r: getattr(r, "outcome", ""),
        short_text=lambda r: SHORT_OUTCOME.get(getattr(r, "outcome", ""), ""),
    ),
    _TIME,
    _FINAL,
    _XTE,
    _XTE95,
    _RATIO,
    _SMOOTH,
    _AVG,
    *_TAIL,
)  # std e_d left out: a run row is wide already (stats --by run prints all nine)
COMPACT_UNITS = "m: final e_xt p95xt e_d p95, rad: |e_θ|, s: t, n: samples"
# Left out of the compact view (80 columns): the mission (a group row instead), and the figures the
# stats cards (the seed's std and path) or the full view (path ratio, smoothness) show
COMPACT_OMITS = ("mission", "stdDevError", "totalPathLength", "path_ratio", "mean_abs_dw_dt")
SORTABLE = {c.key for c in RUN_COLUMNS + ALGORITHM_COLUMNS}


@dataclass(frozen=True, slots=True)
class Table:
    """Rows of cells. Full: a mission column, units in the headers, ``◆`` after a column's best value.
    Compact (narrow terminals): missions as group rows (``group_rows``), short headers, the best values
    listed in ``marked`` (column indices per row) for the screen to show in reverse video."""

    headers: tuple[str, ...]
    keys: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    best: str | None  # the best overall by ranking.RULE_OVERALL, or None (then ``overall`` says why)
    overall: str  # the overall answer in words
    rule: str
    compact: bool = False
    group_rows: tuple[int, ...] = ()  # compact: indices of the rows that name a mission
    marked: tuple[tuple[int, ...], ...] = ()  # compact: the best cells of each row


def sort_value(row: Row, key: str) -> tuple[bool, float | str] | tuple[bool, bool, float]:
    """Missing values last; text columns alphabetically."""
    if key == RANK:
        return ranking.rank_key(row)
    if key in TRACKING_FIELDS:
        tracked = column_value(row, key)
        return (True, 0.0) if tracked is None else (False, tracked)
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
    compact: bool = False,
) -> Table:
    """Rows grouped by mission (in the order missions were first driven; manual driving last), sorted
    within each mission; ``★`` on each mission's best, the overall best by ``ranking.RULE_OVERALL``."""
    columns: tuple[Column, ...] = ALGORITHM_COLUMNS if mode == BY_ALGORITHM else RUN_COLUMNS
    if compact:
        columns = tuple(c for c in columns if c.key not in COMPACT_OMITS)
    source: list[Row] = list(algorithms if mode == BY_ALGORITHM else runs)
    groups: dict[tuple[bool, str], list[Row]] = {}
    for item in source:
        groups.setdefault((item.algorithm == MANUAL, item.mission), []).append(item)
    items: list[Row] = []
    for key in sorted(groups, key=lambda k: k[0]):  # stable: first-seen order, manual last
        items.extend(sorted(groups[key], key=lambda r: sort_value(r, sort), reverse=descending))
    tops = {id(b) for g in ranking.by_mission(items).values() if (b := ranking.best_in(g)) is not None}
    marks = best_in_columns(items, LOWER_IS_BETTER)
    rows: list[tuple[str, ...]] = []
    group_rows: list[int] = []
    marked: list[tuple[int, ...]] = []
    star = next(i for i, c in enumerate(columns) if c.key == "algorithm")
    previous: str | None = None
    for i, item in enumerate(items):
        if compact and item.mission != previous:
            group_rows.append(len(rows))
            rows.append(tuple(item.mission or MANUAL if k == star else "" for k in range(len(columns))))
            marked.append(())
        previous = item.mission
        cells = []
        best_cells = []
        for j, c in enumerate(columns):
            text = (c.short_text or c.text)(item) if compact else c.text(item)
            if i in marks.get(c.key, ()):
                if compact:
                    best_cells.append(j)
                else:
                    text = f"{text} {BEST_CELL}"
            cells.append(text)
        if id(item) in tops:
            cells[star] = f"{BEST_ROW} {cells[star]}"
        elif compact:
            cells[star] = f"  {cells[star]}"  # under the group's name, as the best one is
        rows.append(tuple(cells))
        marked.append(tuple(best_cells))
    overall = ranking.rank(algorithms if algorithms else runs).overall
    return Table(
        headers=tuple((c.short or c.header) if compact else c.header for c in columns),
        keys=tuple(c.key for c in columns),
        rows=tuple(rows),
        best=overall.best,
        overall=overall.reason,
        rule=ranking.RULE_MISSION,
        compact=compact,
        group_rows=tuple(group_rows),
        marked=tuple(marked),
    )


def width(table: Table, padding: int = 1, marks: int = 2) -> int:
    """Columns the table takes, every cell whole: each column as wide as its header (with ``marks`` more
    for a sort mark) or its widest cell, plus ``padding`` on each side."""
    columns = zip(table.headers, *table.rows, strict=True) if table.rows else ((h,) for h in table.headers)
    return sum(max(len(column[0]) + marks, *(len(c) for c in column)) + 2 * padding for column in columns)


def legend(table: Table) -> str:
    """The rule, the overall answer and (compact) the units, as the screen shows them under the table."""
    if table.compact:
        return (
            f"{BEST_ROW} mission best (completed, lowest avg e_xt) · overall: {table.overall} · "
            f"reversed: column best · {COMPACT_UNITS}"
        )
    return (
        f"{BEST_ROW} best of its mission ({table.rule.removeprefix('per mission: ')}) · overall: "
        f"{table.overall} · {BEST_CELL} best of its column in its mission"
    )
