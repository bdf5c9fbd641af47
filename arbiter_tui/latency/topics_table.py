"""The topics screen's table as data: which rows a filter keeps, in what order, each cell's text. Pure."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

from arbiter_core.topicstats import TopicFigures

# sort name -> (key, descending first): the busiest, most delayed, oldest first; names A to Z
SORTS: dict[str, tuple[Callable[[TopicFigures], float | str], bool]] = {
    "name": (lambda t: t.name, False),
    "rate": (lambda t: -1.0 if t.rate_hz is None else t.rate_hz, True),
    "bandwidth": (lambda t: -1.0 if t.bandwidth_bps is None else t.bandwidth_bps, True),
    "delay": (lambda t: -1.0 if t.delay_mean_ms is None else t.delay_mean_ms, True),
    "age": (lambda t: math.inf if t.age_ms is None else t.age_ms, True),
}
SORT_ORDER = tuple(SORTS)
COLUMNS = ("topic", "type", "state", "Hz", "usual", "B/s", "size", "delay", "age", "pub/sub")
TEXT_COLUMNS = ("topic", "type", "state")  # left-aligned; the figures are right-aligned
SORT_COLUMNS = {"name": "topic", "rate": "Hz", "bandwidth": "B/s", "delay": "delay", "age": "age"}
DOWN, UP = "▼", "▲"  # the sorted column's mark: largest (or Z) first, smallest (or A) first
ABSENT = "—"  # a figure that was not measured: never a unit after it


def headers(sort: str, reverse: bool = False) -> tuple[str, ...]:
    """The column names, the sorted one marked with the order shown (``Hz ▼``: the busiest first)."""
    column, descending = SORT_COLUMNS[sort], SORTS[sort][1]
    mark = DOWN if descending != reverse else UP
    return tuple(f"{c} {mark}" if c == column else c for c in COLUMNS)


def unit(value: str, suffix: str) -> str:
    """``value`` followed by its unit, unless it is absent."""
    return value if value == ABSENT else f"{value}{suffix}"


def aligned(value: str, width: int, column: str) -> str:
    """One cell padded to ``width`` (cut with an ellipsis when longer), aligned as its column is."""
    value = value if len(value) <= width else value[: width - 1] + "…"
    return value.ljust(width) if column in TEXT_COLUMNS else value.rjust(width)


# the state a row is marked with (a word, and a style the screen maps to colour): never colour alone
MARKS = {
    "ok": "", "slow": "slow", "silent": "SILENT", "quiet": "quiet", "waiting": "waiting", "unmeasured": "n/a",
    "unknown": "unknown",
}  # fmt: skip
STATE_NOTES = {  # the detail pane's word on what a state means
    "silent": "steady until it stopped: 5 of its periods without a message",
    "quiet": "nothing in the window; it publishes on demand or in bursts, not a fault",
}


def select(topics: Iterable[TopicFigures], text: str, sort: str, reverse: bool = False) -> list[TopicFigures]:
    """The rows whose name or type contains every word of ``text`` (case-insensitive), sorted by ``sort``
    (ties by name); ``reverse`` flips the sort's natural order."""
    words = text.lower().split()
    kept = [t for t in topics if all(w in f"{t.name} {t.type}".lower() for w in words)]
    key, descending = SORTS[sort]
    kept.sort(key=lambda t: t.name)
    kept.sort(key=key, reverse=descending != reverse)
    return kept


def short_type(type_name: str) -> str:
    """sensor_msgs/msg/LaserScan -> sensor_msgs/LaserScan"""
    return type_name.replace("/msg/", "/")


def rate(hz: float | None) -> str:
    if hz is None:
        return ABSENT
    return f"{hz:.0f}" if hz >= 100 else f"{hz:.1f}" if hz >= 10 else f"{hz:.2f}"


def size(n: float | None) -> str:
    """Bytes with a binary-ish unit: 512, 1.4k, 1.0M."""
    if n is None:
        return ABSENT
    for suffix, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if n >= scale:
            return f"{n / scale:.1f}{suffix}"
    return f"{n:.0f}"


def ms(v: float | None) -> str:
    if v is None:
        return ABSENT
    if v >= 10_000:
        return f"{v / 1000:.0f}s"
    if v >= 1000:
        return f"{v / 1000:.1f}s"
    return f"{v:.1f}ms" if v < 100 else f"{v:.0f}ms"


FRESH_MS = 100.0  # an age below this is shown as "<0.1s": a 50 Hz topic's age would change every poll


def age(v: float | None) -> str:
    if v is None:
        return ABSENT
    return "<0.1s" if v < FRESH_MS else ms(v)


def cells(t: TopicFigures) -> tuple[str, ...]:
    return (
        t.name,
        short_type(t.type),
        MARKS[t.state] or "ok",
        rate(t.rate_hz),
        rate(t.usual_rate_hz),
        size(t.bandwidth_bps),
        size(t.mean_size_bytes),
        ms(t.delay_mean_ms) if t.stamped else "",
        age(t.age_ms),
        f"{t.publishers}/{t.subscribers}",
    )


def detail(t: TopicFigures, window_s: float) -> list[str]:
    """The detail pane's lines for one topic."""
    note = t.note or STATE_NOTES.get(t.state)
    lines = [t.name, f"type {t.type}", f"state {t.state}" + (f" ({note})" if note else "")]
    lines.append(f"publishers {t.publishers}  subscribers {t.subscribers}")
    if t.publisher_nodes:
        lines.append("  published by " + ", ".join(t.publisher_nodes))
    if t.subscriber_nodes:
        lines.append("  subscribed by " + ", ".join(t.subscriber_nodes))
    if t.rate_hz is not None:
        lines.append(f"rate {rate(t.rate_hz)} Hz over {t.count} msgs in {window_s:g} s")
        lines.append(
            f"period min {ms(t.period_min_ms)}  max {ms(t.period_max_ms)}  std {ms(t.period_std_ms)}"
        )
    else:
        lines.append(f"rate {ABSENT} ({t.count} msgs in the last {window_s:g} s, {t.total} in all)")
    if t.usual_rate_hz is not None:
        lines.append(f"usual {rate(t.usual_rate_hz)} Hz")
    bandwidth, mean_size = unit(size(t.bandwidth_bps), "B/s"), unit(size(t.mean_size_bytes), "B")
    lines.append(f"bandwidth {bandwidth}  mean size {mean_size}")
    if t.stamped:
        lines.append(f"delay mean {ms(t.delay_mean_ms)}  p95 {ms(t.delay_p95_ms)} (now - header.stamp)")
    if t.malformed_stamps:
        lines.append(f"malformed stamps {t.malformed_stamps}")
    lines.append(f"last message {age(t.age_ms)} ago" if t.age_ms is not None else "no message yet")
    if t.qos_note:
        lines.append(f"QoS: {t.qos_note}")
    return lines


ECHO_MAX_BYTES = 64_000  # larger messages are not echoed: base64 JSON of a camera frame at 2 Hz is MB/s
ECHO_CHARS = 800


def echo_refusal(t: TopicFigures) -> str | None:
    """Why the latest message of ``t`` is not echoed, or None when it may be."""
    if t.state == "unmeasured":
        return "not echoed: the type is not installed on the backend"
    if t.mean_size_bytes is not None and t.mean_size_bytes > ECHO_MAX_BYTES:
        return f"not echoed: messages of {size(t.mean_size_bytes)}B (more than {size(ECHO_MAX_BYTES)}B)"
    return None


def echo_text(msg: object, limit: int = ECHO_CHARS) -> str:
    """A message as compact JSON, cut to ``limit`` characters."""
    import json

    text = json.dumps(msg, separators=(",", ":"), default=str)
    return text if len(text) <= limit else text[: limit - 1] + "…"
