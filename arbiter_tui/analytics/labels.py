"""How the nine AnalyticsStats are named and shown: one table for the analytics screen and ``stats``."""

from __future__ import annotations

from dataclasses import dataclass

from .store import STATS_FIELDS


@dataclass(frozen=True, slots=True)
class StatLabel:
    short: str  # card and column label on screen
    unit: str  # "" for a count
    decimals: int  # on screen; ``stats`` prints 6


STAT_LABELS: dict[str, StatLabel] = {
    "sampleCount": StatLabel("samples", "", 0),
    "avgLinearVel": StatLabel("avg |v|", "m/s", 3),
    "avgAngularVel": StatLabel("avg |ω|", "rad/s", 3),
    "maxLinearVel": StatLabel("max |v|", "m/s", 3),
    "avgDistanceError": StatLabel("avg e_d", "m", 3),
    "avgHeadingError": StatLabel("avg |e_θ|", "rad", 3),
    "stdDevError": StatLabel("std e_d", "m", 3),
    "p95Error": StatLabel("p95 e_d", "m", 3),
    "totalPathLength": StatLabel("path", "m", 2),
}
assert tuple(STAT_LABELS) == STATS_FIELDS, "one label per AnalyticsStats field, in the seed's order"


# The stats measured against a reference (the goal, as the seed's errors are): with none, there is no
# error to measure, and they are shown "—" with why (``no_reference``), null in JSON, never 0
ERROR_FIELDS = ("avgDistanceError", "avgHeadingError", "stdDevError", "p95Error")
NO_VALUE = "—"


def format_stat(
    name: str, value: float, decimals: int | None = None, unit: bool = True, no_reference: str = ""
) -> str:
    """``value`` of stat ``name`` as text: a count as an integer, anything else with its unit; an error
    stat "—" where ``no_reference`` says why there is no reference to measure it against."""
    label = STAT_LABELS[name]
    if no_reference and name in ERROR_FIELDS:
        return NO_VALUE
    if name == "sampleCount":
        return str(int(value))
    text = f"{value:.{label.decimals if decimals is None else decimals}f}"
    return f"{text} {label.unit}" if unit and label.unit else text
