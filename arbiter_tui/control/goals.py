"""A typed goal, ``x y`` in metres in the odometry frame: parsed here, pure, with a one-line error."""

from __future__ import annotations

import math
import re

GOAL_LIMIT_M = 1000.0  # further than any indoor robot drives on a mission from a console
_SPLIT = re.compile(r"[\s,;]+")


class GoalError(ValueError):
    """Why a typed goal is not one; the text says what to type."""


def parse_goal(text: str) -> tuple[float, float]:
    """``"1.5 -2"``, ``"1.5, -2"`` or ``"(1.5, -2)"`` -> (1.5, -2.0)."""
    parts = [p for p in _SPLIT.split(text.strip().strip("()[]")) if p]
    if len(parts) != 2:
        raise GoalError("type two numbers: x y (metres, odometry frame), e.g. 1.5 -0.5")
    try:
        x, y = (float(p) for p in parts)
    except ValueError:
        raise GoalError(f"not numbers: {text.strip()[:40]!r}; type x y, e.g. 1.5 -0.5") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise GoalError("the goal must be finite")
    if max(abs(x), abs(y)) > GOAL_LIMIT_M:
        raise GoalError(f"the goal is more than {GOAL_LIMIT_M:g} m away from the origin")
    return x, y
