"""The truth of a topic's rate, from the times its messages were really sent (or heard by an independent
subscriber): the monitor's definition, (n - 1) / span, applied to those times. Shared by the robot-graph
test and its benchmark."""

from __future__ import annotations


def truth_rate(times: list[float], start: float, end: float) -> float | None:
    """(n - 1) / span of the publishes inside [start, end]: the monitor's definition, on what was sent."""
    t = [x for x in times if start <= x <= end]
    if len(t) < 3:
        return None
    return (len(t) - 1) / (t[-1] - t[0])


def steady(times: list[float], start: float, end: float) -> float | None:
    """The true rate over [start, end] of a topic that flowed through the whole of it (its messages span
    most of the window and the last is recent); None for one that started, stopped or is too sparse in
    it (a goal's topics, a latched one), whose rate over a window says little."""
    rate = truth_rate(times, start, end)
    if rate is None:
        return None
    t = [x for x in times if start <= x <= end]
    if t[-1] - t[0] < 0.7 * (end - start) or end - t[-1] > 2.5 / rate:
        return None
    return rate
