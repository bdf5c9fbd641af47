"""A typed goal, ``x y`` in metres in the odometry frame: parsed here, pure, with a one-line error."""

from __future__ import annotations

import math
import re

GOAL_LIMIT_M = 1000.0  # further than any indoor robot drives on a mission from a console
GOAL_CONFIRM_M = 20.0  # a typed goal further than this from the robot is asked about before it drives
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


def far_goal(goal: tuple[float, float], robot: tuple[float, float]) -> str | None:
    """What to ask before driving to a ``goal`` more than ``GOAL_CONFIRM_M`` from the ``robot`` (a typo,
    a goal in another frame); None for a goal within it."""
    d = math.hypot(goal[0] - robot[0], goal[1] - robot[1])
    if d <= GOAL_CONFIRM_M:
        return None
    return f"({goal[0]:+.2f}, {goal[1]:+.2f}) is {d:.0f} m from the robot: enter again to drive there"
