"""Serialise and parse analytics exports (pure: text/bytes in and out, no files).

* CSV: the seed's header line and column order, numbers as JavaScript prints them.
* JSON: ``{"dataPoints": [...], "stats": {...}}`` with the seed's camelCase keys; strict
  (no NaN/Infinity tokens; an unknown latency is ``null``).
* MCAP: one ROS 2 (CDR) message per data point on ``/arbiter/data_point`` with an explicit
  message definition, plus the stats on ``/arbiter/stats``; Foxglove and PlotJuggler open it.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from typing import Any

from .store import FIELDS, NUMERIC, STATS_FIELDS, AnalyticsStats, DataPoint, stats_of_points

CSV_HEADER = ",".join(FIELDS)
MCAP_POINT_TOPIC = "/arbiter/data_point"
MCAP_STATS_TOPIC = "/arbiter/stats"
MCAP_POINT_TYPE = "arbiter_msgs/msg/DataPoint"
MCAP_STATS_TYPE = "arbiter_msgs/msg/AnalyticsStats"
MCAP_POINT_DEF = "\n".join(
    [
        "float64 timestamp  # ms since the epoch",
        "float64 x",
        "float64 y",
        "float64 theta",
        "float64 linear_vel",
        "float64 angular_vel",
        "float64 distance_error",
        "float64 heading_error",
        "string algorithm",
        "float64 latency_ms  # NaN when unknown",
        "bool has_latency",
    ]
)
MCAP_STATS_DEF = "\n".join(
    ["uint32 sample_count"]
    + [
        f"float64 {n}"
        for n in (
            "avg_linear_vel",
            "avg_angular_vel",
            "max_linear_vel",
            "avg_distance_error",
            "avg_heading_error",
            "std_dev_error",
            "p95_error",
            "total_path_length",
        )
    ]
)


class ExportFormatError(ValueError):
    """An export file that cannot be read back."""


def js_number(value: float | int | None) -> str:
    """Format a number as JavaScript's ``String(n)`` would for the values we export."""
    if value is None:
        return ""
    f = float(value)
    if not math.isfinite(f):
        raise ValueError(f"cannot export non-finite value {value!r}")
    if f.is_integer() and abs(f) < 1e21:
        return str(int(f))
    r = repr(f)
    if "e" in r:
        mant, exp = r.split("e")
        r = f"{mant}e{'+' if int(exp) > 0 else '-'}{abs(int(exp))}"
    return r


def to_csv(points: Sequence[DataPoint]) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    out.write(CSV_HEADER + "\n")
    for p in points:
        writer.writerow([p.algorithm if f == "algorithm" else js_number(getattr(p, f)) for f in FIELDS])
    return out.getvalue()


def to_json(points: Sequence[DataPoint], stats: AnalyticsStats | None = None) -> str:
    if stats is None:
        stats = stats_of_points(points)
    doc = {"dataPoints": [p.as_dict() for p in points], "stats": stats.as_dict()}
    return json.dumps(doc, allow_nan=False, indent=1) + "\n"


def to_mcap(points: Sequence[DataPoint], stats: AnalyticsStats | None = None) -> bytes:
    from mcap_ros2.writer import Writer

    if stats is None:
        stats = stats_of_points(points)
    rows = [_mcap_point(p) for p in points]  # validate everything before writing a byte
    stats_row = _mcap_stats(stats)
    buf = io.BytesIO()
    writer = Writer(buf)
    point_schema = writer.register_msgdef(MCAP_POINT_TYPE, MCAP_POINT_DEF)
    stats_schema = writer.register_msgdef(MCAP_STATS_TYPE, MCAP_STATS_DEF)
    last_ns = 0
    for p, row in zip(points, rows, strict=False):
        t_ns = max(0, int(p.timestamp * 1_000_000))
        last_ns = max(last_ns, t_ns)
        writer.write_message(MCAP_POINT_TOPIC, point_schema, row, log_time=t_ns, publish_time=t_ns)
    writer.write_message(MCAP_STATS_TOPIC, stats_schema, stats_row, log_time=last_ns, publish_time=last_ns)
    writer.finish()
    return buf.getvalue()


MCAP_MAGIC = b"\x89MCAP0\r\n"


def parse_mcap(data: bytes) -> list[DataPoint]:
    """The DataPoints of an MCAP export (the ``/arbiter/data_point`` channel; other channels ignored)."""
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    if not data.startswith(MCAP_MAGIC):
        raise ExportFormatError("not an MCAP file")
    points: list[DataPoint] = []
    try:
        reader = make_reader(io.BytesIO(data), decoder_factories=[DecoderFactory()])
        for _schema, _channel, _message, m in reader.iter_decoded_messages(topics=[MCAP_POINT_TOPIC]):
            where = f"MCAP message {len(points) + 1}"
            row = {
                "timestamp": m.timestamp,
                "x": m.x,
                "y": m.y,
                "theta": m.theta,
                "linearVel": m.linear_vel,
                "angularVel": m.angular_vel,
                "distanceError": m.distance_error,
                "headingError": m.heading_error,
                "algorithm": m.algorithm,
                "latencyMs": m.latency_ms if m.has_latency else None,
            }
            points.append(_point_from_mapping(row, where))
    except (McapError, AttributeError, ValueError, EOFError) as exc:
        if isinstance(exc, ExportFormatError):
            raise
        raise ExportFormatError(f"not an arbiter MCAP export: {exc}") from None
    return points


def _mcap_point(p: DataPoint) -> dict[str, Any]:
    p.validate()  # the CDR writer silently zero-fills missing fields: refuse them here
    return {
        "timestamp": float(p.timestamp),
        "x": float(p.x),
        "y": float(p.y),
        "theta": float(p.theta),
        "linear_vel": float(p.linearVel),
        "angular_vel": float(p.angularVel),
        "distance_error": float(p.distanceError),
        "heading_error": float(p.headingError),
        "algorithm": p.algorithm,
        "latency_ms": math.nan if p.latencyMs is None else float(p.latencyMs),
        "has_latency": p.latencyMs is not None,
    }


def _mcap_stats(s: AnalyticsStats) -> dict[str, Any]:
    values = [getattr(s, f) for f in STATS_FIELDS[1:]]
    if not all(math.isfinite(v) for v in values) or s.sampleCount < 0:
        raise ValueError("stats must be finite")
    names = MCAP_STATS_DEF.split("\n")
    return {"sample_count": int(s.sampleCount)} | {
        line.split()[1]: float(v) for line, v in zip(names[1:], values, strict=False)
    }


# -- reading exports back ------------------------------------------------------------


def _point_from_mapping(row: dict[str, Any], where: str) -> DataPoint:
    values: dict[str, Any] = {}
    for f in FIELDS:
        if f not in row:
            raise ExportFormatError(f"{where}: missing field {f!r}")
        raw = row[f]
        if f == "algorithm":
            if not isinstance(raw, str) or not raw:
                raise ExportFormatError(f"{where}: algorithm must be a non-empty string")
            values[f] = raw
            continue
        if f == "latencyMs" and (raw is None or raw == ""):
            values[f] = None
            continue
        if isinstance(raw, str):
            try:
                raw = float(raw)
            except ValueError:
                raise ExportFormatError(f"{where}: {f} is not a number: {raw[:40]!r}") from None
        if isinstance(raw, bool) or not isinstance(raw, (int, float)):
            raise ExportFormatError(f"{where}: {f} must be a number")
        if not math.isfinite(raw):
            raise ExportFormatError(f"{where}: {f} is not finite")
        values[f] = float(raw)
    return DataPoint(**values)


def parse_csv(text: str) -> list[DataPoint]:
    lines = text.splitlines()
    if not lines:
        raise ExportFormatError("empty file")
    if lines[0].strip().lstrip("\ufeff") != CSV_HEADER:
        raise ExportFormatError(f"not an arbiter analytics CSV: header must be {CSV_HEADER!r}")
    reader = csv.DictReader(io.StringIO(text.lstrip("\ufeff")))
    points = []
    for i, row in enumerate(reader, start=2):
        if None in row or any(v is None for v in row.values()):
            raise ExportFormatError(f"line {i}: expected {len(FIELDS)} columns")
        points.append(_point_from_mapping(row, f"line {i}"))
    return points


def parse_json(text: str) -> list[DataPoint]:
    def reject(token: str) -> Any:
        raise ExportFormatError(f"non-standard JSON token {token}")

    try:
        doc = json.loads(text, parse_constant=reject)
    except ExportFormatError:
        raise
    except (ValueError, RecursionError) as exc:
        raise ExportFormatError(f"invalid JSON: {exc}") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("dataPoints"), list):
        raise ExportFormatError('not an arbiter analytics JSON export: expected {"dataPoints": [...]}')
    out = []
    for i, row in enumerate(doc["dataPoints"]):
        if not isinstance(row, dict):
            raise ExportFormatError(f"dataPoints[{i}] must be an object")
        out.append(_point_from_mapping(row, f"dataPoints[{i}]"))
    return out


def stats_json(stats: AnalyticsStats) -> str:
    return json.dumps(stats.as_dict(), allow_nan=False)


__all__ = [
    "CSV_HEADER",
    "NUMERIC",
    "ExportFormatError",
    "js_number",
    "parse_csv",
    "parse_json",
    "stats_json",
    "to_csv",
    "to_json",
    "to_mcap",
]
