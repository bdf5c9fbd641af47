"""The stamped-command envelope carried as ``std_msgs/String`` data on ``/stamped_cmd_vel``.

Wire form (the seed's, extended with an optional sequence number)::

    {"header": {"stamp": 1712345678901.234, "seq": 7, "offset_ms": -3.2},
     "twist": {"linear": {"x": 0.5}, "angular": {"z": 0.0}}}

``stamp`` is wall-clock milliseconds since the epoch. We send a float with
microsecond resolution; the seed sends integer milliseconds and both parse.
``offset_ms`` is optional: the sender's estimate of the receiver's clock minus
its own (from round trips), which the tracker uses to judge a command's age.
Parsing takes untrusted text and either returns a :class:`StampedCommand` or
raises :class:`EnvelopeError` with a ``kind`` naming the class of problem. It
never raises anything else.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

MAX_ENVELOPE_BYTES = 64 * 1024
MAX_OFFSET_MS = 86_400_000.0  # a clock a day off is not an offset estimate


class EnvelopeError(ValueError):
    """A stamped command that cannot be accepted. ``kind`` is a stable short code."""

    KINDS = ("too_large", "invalid_json", "not_object", "missing_field", "bad_type", "non_finite")

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


@dataclass(frozen=True)
class StampedCommand:
    stamp_ms: float
    linear_x: float
    angular_z: float
    seq: int | None = None
    offset_ms: float | None = None  # the sender's estimate of (receiver clock - sender clock)


def stamp_ms_from_ns(ns: int) -> float:
    """Wall-clock ns -> ms as a float, truncated to whole microseconds."""
    return (ns // 1000) / 1000.0


def build(
    linear_x: float,
    angular_z: float,
    seq: int | None = None,
    clock_ns: Callable[[], int] = time.time_ns,
    offset_ms: float | None = None,
) -> str:
    """Serialise a stamped command; the stamp is taken from ``clock_ns`` at call time."""
    if not (math.isfinite(linear_x) and math.isfinite(angular_z)):
        raise EnvelopeError("non_finite", "velocities must be finite numbers")
    header: dict[str, Any] = {"stamp": stamp_ms_from_ns(clock_ns())}
    if seq is not None:
        header["seq"] = int(seq)
    if offset_ms is not None and math.isfinite(offset_ms) and abs(offset_ms) <= MAX_OFFSET_MS:
        header["offset_ms"] = round(float(offset_ms), 3)
    return json.dumps(
        {"header": header, "twist": {"linear": {"x": float(linear_x)}, "angular": {"z": float(angular_z)}}},
        separators=(",", ":"),
        allow_nan=False,
    )


def _reject_constant(token: str) -> Any:
    raise EnvelopeError("non_finite", f"non-finite number {token} in envelope")


_DECODER = json.JSONDecoder(parse_constant=_reject_constant)  # made once: json.loads(kw) makes one per call


def _get(obj: Any, path: tuple[str, ...]) -> Any:
    cur = obj
    walked: list[str] = []
    for key in path:
        if not isinstance(cur, dict):
            where = ".".join(walked) or "envelope"
            raise EnvelopeError("bad_type", f"{where} must be an object, got {type(cur).__name__}")
        walked.append(key)
        if key not in cur:
            raise EnvelopeError("missing_field", f"missing field {'.'.join(walked)}")
        cur = cur[key]
    return cur


def _number(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise EnvelopeError("bad_type", f"{name} must be a number, got {type(value).__name__}")
    try:
        f = float(value)
    except OverflowError:
        raise EnvelopeError("non_finite", f"{name} is out of range") from None
    if not math.isfinite(f):
        raise EnvelopeError("non_finite", f"{name} must be finite")
    return f


def parse(text: str | bytes) -> StampedCommand:
    """Parse and validate an envelope from untrusted text."""
    if isinstance(text, bytes):
        if len(text) > MAX_ENVELOPE_BYTES:
            raise EnvelopeError("too_large", f"envelope is {len(text)} bytes, limit {MAX_ENVELOPE_BYTES}")
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError:
            raise EnvelopeError("invalid_json", "envelope is not UTF-8 text") from None
    if not isinstance(text, str):
        raise EnvelopeError("bad_type", f"envelope must be text, got {type(text).__name__}")
    if len(text) > MAX_ENVELOPE_BYTES or len(text.encode("utf-8", "surrogatepass")) > MAX_ENVELOPE_BYTES:
        raise EnvelopeError("too_large", f"envelope exceeds {MAX_ENVELOPE_BYTES} bytes")
    try:
        obj = _DECODER.decode(text)
    except EnvelopeError:
        raise
    except (ValueError, RecursionError) as exc:
        raise EnvelopeError("invalid_json", f"invalid JSON: {exc}") from None
    if not isinstance(obj, dict):
        raise EnvelopeError("not_object", f"envelope must be a JSON object, got {type(obj).__name__}")
    stamp = _number(_get(obj, ("header", "stamp")), "header.stamp")
    linear = _number(_get(obj, ("twist", "linear", "x")), "twist.linear.x")
    angular = _number(_get(obj, ("twist", "angular", "z")), "twist.angular.z")
    seq: int | None = None
    header = obj["header"]
    if "seq" in header:
        raw = header["seq"]
        if isinstance(raw, bool) or not isinstance(raw, int):
            raise EnvelopeError("bad_type", f"header.seq must be an integer, got {type(raw).__name__}")
        seq = raw
    offset: float | None = None
    if "offset_ms" in header:
        offset = _number(header["offset_ms"], "header.offset_ms")
        if abs(offset) > MAX_OFFSET_MS:
            raise EnvelopeError("bad_type", f"header.offset_ms must be within ±{MAX_OFFSET_MS:.0f}")
    return StampedCommand(stamp_ms=stamp, linear_x=linear, angular_z=angular, seq=seq, offset_ms=offset)
