"""The latency tracker's record (:class:`LatencyRecord`) and its stats block (the seed's
``latency_tracker.py`` shapes)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

from .envelope import StampedCommand
from .stats import ArrayLike, Summary, summarize

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


class RecordError(ValueError):
    """A latency record (from the API or ``/latency_report``) that does not have the seed's shape."""


@dataclass(frozen=True, slots=True)
class LatencyRecord:
    """One command as the tracker saw it: the seed's five fields, plus ``seq`` (the sender's, when its
    envelope carried one), ``stale`` (dropped as too old, never forwarded) and ``rx_seq`` (the
    tracker's receive counter, 1-based, across all senders: what ``GET /api/latency?since=`` pages by).

    ``t_recv_ms`` and ``t_sent_ms`` are NTP's t1 and t2: the tracker's wall clock (epoch **milliseconds**,
    whole microseconds) when the command arrived and when this report was handed to the transport. With
    the sender's t0 (its stamp) and t3 (report arrival) they give the round trip *minus the time spent
    inside the tracker*, and the clock offset without it (``arbiter_core.clockmodel``). Additive: a
    client reading the seed's five fields never sees them; a seed tracker's records do not have them.

    Built once by the tracker, serialised once (:meth:`to_json`) for the API and ``/latency_report``,
    parsed by the console (:meth:`from_obj`). The JSON is the seed's, extras only when set.
    """

    latency_ms: float
    linear_x: float
    angular_z: float
    timestamp: float  # receive time, epoch seconds
    deploy_mode: str
    seq: int | None = None
    stale: bool = False
    rx_seq: int | None = None
    t_recv_ms: float | None = None  # NTP t1: tracker receive wall time, epoch ms (µs resolution)
    t_sent_ms: float | None = None  # NTP t2: tracker wall time the report was handed to the transport

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "latency_ms": self.latency_ms,
            "linear_x": self.linear_x,
            "angular_z": self.angular_z,
            "timestamp": self.timestamp,
            "deploy_mode": self.deploy_mode,
        }
        if self.seq is not None:
            out["seq"] = self.seq
        if self.stale:
            out["stale"] = True
        if self.rx_seq is not None:
            out["rx_seq"] = self.rx_seq
        if self.t_recv_ms is not None:
            out["t_recv_ms"] = self.t_recv_ms
        if self.t_sent_ms is not None:
            out["t_sent_ms"] = self.t_sent_ms
        return out

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), allow_nan=False, separators=(",", ":"))

    @classmethod
    def from_obj(cls, obj: object) -> LatencyRecord:
        """Parse a decoded record; :class:`RecordError` names the first field that is wrong."""
        if not isinstance(obj, dict):
            raise RecordError(f"a record must be an object, got {type(obj).__name__}")
        deploy_mode = obj.get("deploy_mode")
        if not isinstance(deploy_mode, str):
            raise RecordError("deploy_mode must be a string")
        stale = obj.get("stale", False)
        if not isinstance(stale, bool):
            raise RecordError("stale must be true or false")
        return cls(
            latency_ms=_number(obj, "latency_ms"),
            linear_x=_number(obj, "linear_x"),
            angular_z=_number(obj, "angular_z"),
            timestamp=_number(obj, "timestamp"),
            deploy_mode=deploy_mode,
            seq=_optional_count(obj, "seq"),
            stale=stale,
            rx_seq=_optional_count(obj, "rx_seq"),
            t_recv_ms=_optional_number(obj, "t_recv_ms"),
            t_sent_ms=_optional_number(obj, "t_sent_ms"),
        )

    @classmethod
    def from_json(cls, text: str | bytes) -> LatencyRecord:
        try:
            obj = json.loads(text)
        except (ValueError, TypeError) as exc:
            raise RecordError(f"not JSON: {exc}") from None
        return cls.from_obj(obj)


def _number(obj: dict[str, Any], key: str) -> float:
    value = obj.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise RecordError(f"{key} must be a finite number, got {value!r:.40}")
    return float(value)


def _optional_number(obj: dict[str, Any], key: str) -> float | None:
    return None if obj.get(key) is None else _number(obj, key)


def epoch_ms(ns: int) -> float:
    """Wall time in ns as epoch ms with whole microseconds (what a float of ms can hold exactly enough)."""
    return (ns // 1000) / 1000.0


def _optional_count(obj: dict[str, Any], key: str) -> int | None:
    value = obj.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise RecordError(f"{key} must be a whole number >= 0, got {value!r:.40}")
    return value


def build_record(
    cmd: StampedCommand,
    recv_ns: int,
    deploy_mode: str,
    *,
    stale: bool = False,
    rx_seq: int | None = None,
    sent_ns: int | None = None,
) -> LatencyRecord:
    """The tracker's record of ``cmd`` received at ``recv_ns`` (wall clock, ns); with ``sent_ns`` (the
    wall time its report goes out) it carries both NTP tracker stamps, t1 and t2."""
    return LatencyRecord(
        latency_ms=latency_ms(cmd, recv_ns),
        linear_x=cmd.linear_x,
        angular_z=cmd.angular_z,
        timestamp=recv_ns / 1e9,
        deploy_mode=deploy_mode,
        seq=cmd.seq,
        stale=stale,
        rx_seq=rx_seq,
        t_recv_ms=None if sent_ns is None else epoch_ms(recv_ns),
        t_sent_ms=None if sent_ns is None else epoch_ms(sent_ns),
    )


def latency_stats(latencies: ArrayLike) -> dict[str, Any]:
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


def parse_latency_stats(obj: Any) -> Summary:
    """A tracker's stats block (:func:`latency_stats`) back into a :class:`Summary`; a block with count 0
    is the empty summary. Raises :class:`RecordError` naming the field that is not a number."""
    if not isinstance(obj, dict):
        raise RecordError(f"stats must be an object, got {type(obj).__name__}")
    count = obj.get("count")
    if not isinstance(count, int) or isinstance(count, bool) or count < 0:
        raise RecordError(f"stats.count must be a whole number >= 0, got {count!r:.40}")
    if count == 0:
        return summarize(())
    values = []
    for key in ("mean_ms", "min_ms", "max_ms", "p95_ms", "stddev_ms"):
        v = obj.get(key)
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
            raise RecordError(f"stats.{key} must be a finite number, got {v!r:.40}")
        values.append(float(v))
    return Summary(count, *values)
