"""Serialise and parse analytics exports (pure: text/bytes in and out, no files).

* CSV: the seed's ten columns in its order, numbers as JavaScript prints them, then ours: ``runId``
  (empty outside a run). The seed's own CSV (ten columns) reads back too.
* JSON: ``{"dataPoints": [...], "stats": {...}, "runs": [...]}`` with the seed's camelCase keys (each
  point also carries ``runId``); strict (no NaN/Infinity tokens; an unknown latency is ``null``).
* MCAP (ROS 2 CDR, explicit message definitions): the data points on ``/arbiter/data_point``, the stats
  on ``/arbiter/stats``, the run summaries on ``/arbiter/runs``, and the robot's pose and commanded twist
  as standard ``nav_msgs/msg/Odometry`` on ``/arbiter/odom`` (frame ``odom``, child ``base_link``), so
  Foxglove's 3D panel draws the path and PlotJuggler plots it without our message types.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from typing import Any

from .model import EXTRA_FIELDS, FIELDS, NUMERIC, STATS_FIELDS, AnalyticsStats, DataPoint, stats_of_points
from .runs import RunSummary

SEED_CSV_HEADER = ",".join(FIELDS)
CSV_HEADER = ",".join(FIELDS + EXTRA_FIELDS)
MCAP_RUNS_TOPIC = "/arbiter/runs"
MCAP_ODOM_TOPIC = "/arbiter/odom"
MCAP_RUN_TYPE = "arbiter_msgs/msg/RunSummary"
MCAP_ODOM_TYPE = "nav_msgs/msg/Odometry"
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
        "uint32 run_id  # 0 outside every run",
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

_SEP = "=" * 80
MCAP_RUN_DEF = "\n".join(
    [
        "uint32 id",
        "string algorithm",
        "string mission  # empty for manual driving",
        "string outcome  # running, completed, aborted, overridden, ended",
        "bool completed",
        "float64 start_ms",
        "float64 end_ms  # NaN while running",
        "float64 time_s",
        "float64 final_error_m  # NaN for manual driving",
        "arbiter_msgs/AnalyticsStats stats  # over all of the run's samples",
        _SEP,
        "MSG: arbiter_msgs/AnalyticsStats",
        MCAP_STATS_DEF,
    ]
)
# nav_msgs/msg/Odometry with its dependencies, in the concatenated form ROS 2 bags store
MCAP_ODOM_DEF = f"""std_msgs/Header header
string child_frame_id
geometry_msgs/PoseWithCovariance pose
geometry_msgs/TwistWithCovariance twist
{_SEP}
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
{_SEP}
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
{_SEP}
MSG: geometry_msgs/PoseWithCovariance
geometry_msgs/Pose pose
float64[36] covariance
{_SEP}
MSG: geometry_msgs/Pose
geometry_msgs/Point position
geometry_msgs/Quaternion orientation
{_SEP}
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
{_SEP}
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
{_SEP}
MSG: geometry_msgs/TwistWithCovariance
geometry_msgs/Twist twist
float64[36] covariance
{_SEP}
MSG: geometry_msgs/Twist
geometry_msgs/Vector3 linear
geometry_msgs/Vector3 angular
{_SEP}
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z"""


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
        row = [p.algorithm if f == "algorithm" else js_number(getattr(p, f)) for f in FIELDS]
        writer.writerow([*row, "" if p.runId is None else str(p.runId)])
    return out.getvalue()


def to_json(
    points: Sequence[DataPoint], stats: AnalyticsStats | None = None, runs: Sequence[RunSummary] = ()
) -> str:
    if stats is None:
        stats = stats_of_points(points)
    doc = {
        "dataPoints": [p.as_dict() for p in points],
        "stats": stats.as_dict(),
        "runs": [r.as_dict() for r in runs],
    }
    return json.dumps(doc, allow_nan=False, indent=1) + "\n"


def to_mcap(
    points: Sequence[DataPoint], stats: AnalyticsStats | None = None, runs: Sequence[RunSummary] = ()
) -> bytes:
    from mcap_ros2.writer import Writer

    if stats is None:
        stats = stats_of_points(points)
    rows = [_mcap_point(p) for p in points]  # validate everything before writing a byte
    stats_row = _mcap_stats(stats)
    run_rows = [_mcap_run(r) for r in runs]
    buf = io.BytesIO()
    writer = Writer(buf)
    point_schema = writer.register_msgdef(MCAP_POINT_TYPE, MCAP_POINT_DEF)
    odom_schema = writer.register_msgdef(MCAP_ODOM_TYPE, MCAP_ODOM_DEF)
    stats_schema = writer.register_msgdef(MCAP_STATS_TYPE, MCAP_STATS_DEF)
    run_schema = writer.register_msgdef(MCAP_RUN_TYPE, MCAP_RUN_DEF)
    last_ns = 0
    for p, row in zip(points, rows, strict=False):
        t_ns = max(0, int(p.timestamp * 1_000_000))
        last_ns = max(last_ns, t_ns)
        writer.write_message(MCAP_POINT_TOPIC, point_schema, row, log_time=t_ns, publish_time=t_ns)
        writer.write_message(
            MCAP_ODOM_TOPIC, odom_schema, _odometry(p, t_ns), log_time=t_ns, publish_time=t_ns
        )
    for r, row in zip(runs, run_rows, strict=True):
        t_ns = max(0, int((r.end_ms if r.end_ms is not None else r.last_ms or r.start_ms) * 1_000_000))
        writer.write_message(MCAP_RUNS_TOPIC, run_schema, row, log_time=t_ns, publish_time=t_ns)
    writer.write_message(MCAP_STATS_TOPIC, stats_schema, stats_row, log_time=last_ns, publish_time=last_ns)
    writer.finish()
    return buf.getvalue()


def _odometry(p: DataPoint, t_ns: int) -> dict[str, Any]:
    """The sample as nav_msgs/Odometry: pose from odometry, twist = the commanded twist (unknown
    covariance: zeros, as most drivers publish)."""
    zeros = [0.0] * 36
    return {
        "header": {"stamp": {"sec": t_ns // 10**9, "nanosec": t_ns % 10**9}, "frame_id": "odom"},
        "child_frame_id": "base_link",
        "pose": {
            "pose": {
                "position": {"x": p.x, "y": p.y, "z": 0.0},
                "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(p.theta / 2), "w": math.cos(p.theta / 2)},
            },
            "covariance": zeros,
        },
        "twist": {
            "twist": {"linear": {"x": p.linearVel, "y": 0.0, "z": 0.0},
                      "angular": {"x": 0.0, "y": 0.0, "z": p.angularVel}},
            "covariance": zeros,
        },
    }  # fmt: skip


def _mcap_run(r: RunSummary) -> dict[str, Any]:
    return {
        "id": r.id,
        "algorithm": r.algorithm,
        "mission": r.mission,
        "outcome": r.outcome,
        "completed": r.completed,
        "start_ms": float(r.start_ms),
        "end_ms": math.nan if r.end_ms is None else float(r.end_ms),
        "time_s": float(r.time_s),
        "final_error_m": math.nan if r.final_error_m is None else float(r.final_error_m),
        "stats": _mcap_stats(r.stats),
    }


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
                "runId": getattr(m, "run_id", 0) or None,  # exports before runs had none
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
        "run_id": p.runId or 0,
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
    return DataPoint(**values, runId=_run_id(row.get("runId"), where))


def _run_id(raw: Any, where: str) -> int | None:
    if raw is None or raw == "":
        return None
    if isinstance(raw, str):
        if not raw.isdigit():
            raise ExportFormatError(f"{where}: runId is not a positive integer: {raw[:40]!r}")
        raw = int(raw)
    if isinstance(raw, bool) or not isinstance(raw, int) or not 1 <= raw < 2**32:
        raise ExportFormatError(f"{where}: runId must be a positive integer")
    return raw


def parse_csv(text: str) -> list[DataPoint]:
    lines = text.splitlines()
    if not lines:
        raise ExportFormatError("empty file")
    header = lines[0].strip().lstrip("\ufeff")
    if header not in (CSV_HEADER, SEED_CSV_HEADER):
        raise ExportFormatError(f"not an arbiter analytics CSV: header must be {CSV_HEADER!r}")
    columns = header.count(",") + 1
    reader = csv.DictReader(io.StringIO(text.lstrip("\ufeff")))
    points = []
    for i, row in enumerate(reader, start=2):
        if None in row or any(v is None for v in row.values()):
            raise ExportFormatError(f"line {i}: expected {columns} columns")
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
    "SEED_CSV_HEADER",
    "ExportFormatError",
    "js_number",
    "parse_csv",
    "parse_json",
    "stats_json",
    "to_csv",
    "to_json",
    "to_mcap",
]
