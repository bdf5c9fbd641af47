"""The latency tracker's record and its stats block (the seed's ``latency_tracker.py`` shapes)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .envelope import StampedCommand
from .stats import summarize

NS_PER_MS = 1_000_000


def latency_ms(cmd: StampedCommand, recv_ns: int) -> float:
    """One-way latency: receive wall time minus the sender's stamp, in ms, rounded to 4 places.

    Stamps carry whole microseconds (a float of ms since the epoch cannot hold more: its
    resolution there is ~0.24 µs), so the stamp is taken back to integer µs first and the
    difference is exact integer arithmetic.
    """
    stamp_ns = round(cmd.stamp_ms * 1000.0) * 1000
    return round((recv_ns - stamp_ns) / NS_PER_MS, 4)


def command_age_ms(cmd: StampedCommand, latency: float) -> float:
    """How old a command is on arrival: its one-way latency, corrected by the sender's clock-offset
    estimate when the envelope carries one (``offset_ms`` = receiver clock minus sender clock)."""
    return latency - (cmd.offset_ms or 0.0)


def build_record(cmd: StampedCommand, recv_ns: int, deploy_mode: str) -> dict[str, Any]:
    """The seed's record: latency_ms, linear_x, angular_z, timestamp (receive epoch s), deploy_mode.

    ``seq`` is added when the envelope carried one.
    """
    record: dict[str, Any] = {
        "latency_ms": latency_ms(cmd, recv_ns),
        "linear_x": cmd.linear_x,
        "angular_z": cmd.angular_z,
        "timestamp": recv_ns / 1e9,
        "deploy_mode": deploy_mode,
    }
    if cmd.seq is not None:
        record["seq"] = cmd.seq
    return record


def latency_stats(latencies: Sequence[float]) -> dict[str, Any]:
    """``{"count", "mean_ms", "min_ms", "max_ms", "p95_ms", "stddev_ms"}``; ms fields null when empty.

    Values are rounded to 4 places, like the records they summarise.
    """
    s = summarize(latencies)
    if s.count == 0:
        return {
            "count": 0,
            "mean_ms": None,
            "min_ms": None,
            "max_ms": None,
            "p95_ms": None,
            "stddev_ms": None,
        }
    return {
        "count": s.count,
        "mean_ms": round(s.mean, 4),
        "min_ms": round(s.min, 4),
        "max_ms": round(s.max, 4),
        "p95_ms": round(s.p95, 4),
        "stddev_ms": round(s.stddev, 4),
    }
