"""Serialise and parse analytics exports (pure: text/bytes in and out, no files).

* CSV: the seed's ten columns in its order, numbers as JavaScript prints them, then ours: ``runId``
  (empty outside a run) and ``gap`` (``1`` where the sample follows a gap in the recording, else
  empty). The seed's own CSV (ten columns) and ours before ``gap`` (eleven) read back too.
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
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import IO, Any

from .model import EXTRA_FIELDS, FIELDS, NUMERIC, STATS_FIELDS, AnalyticsStats, DataPoint, stats_of_points
from .runs import OUTCOMES, AlgorithmSummary, RunSummary
from .tracking import TRACKING_FIELDS, TrackingStats

SEED_CSV_HEADER = ",".join(FIELDS)
CSV_HEADER = ",".join(FIELDS + EXTRA_FIELDS)
RUNS_CSV_HEADER = ",".join((*FIELDS, "runId"))  # ours before the gap column
CSV_HEADERS = (CSV_HEADER, RUNS_CSV_HEADER, SEED_CSV_HEADER)
MCAP_RUNS_TOPIC = "/arbiter/runs"
MCAP_ALGORITHMS_TOPIC = "/arbiter/algorithms"
MCAP_ALGORITHM_TYPE = "arbiter_msgs/msg/AlgorithmSummary"
MCAP_ODOM_TOPIC = "/arbiter/odom"
MCAP_RUN_TYPE = "arbiter_msgs/msg/RunSummary"
MCAP_ODOM_TYPE = "nav_msgs/msg/Odometry"
MCAP_POINT_TOPIC = "/arbiter/data_point"
MCAP_STATS_TOPIC = "/arbiter/stats"
MCAP_POINT_TYPE = "arbiter_msgs/msg/DataPoint"
MCAP_STATS_TYPE = "arbiter_msgs/msg/AnalyticsStats"
MCAP_PLANS_TOPIC = "/arbiter/plans"
MCAP_PLAN_TYPE = "arbiter_msgs/msg/RunPlan"
MCAP_PLAN_DEF = "\n".join(
    [
        "uint32 run_id",
        "float64 timestamp  # when the console took it as the run's reference, epoch ms",
        "float64[] x  # the reference path's positions, m, odometry's frame",
        "float64[] y",
    ]
)
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
        "bool gap  # the sample follows a gap in the recording: no path is counted into it",
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
MCAP_TRACKING_DEF = "\n".join(
    [
        "bool measured  # false: no reference path (manual driving); the figures below are then 0",
        "uint32 samples",
        *(f"float64 {name}" for name in TRACKING_FIELDS[:4]),
        "float64 time_to_complete_s  # NaN unless completed",
        "float64 path_ratio  # NaN when the reference has no length",
        "float64 mean_abs_dw_dt",
        "float64 linear_jerk  # integrated squared jerk of the commanded speed, m^2/s^5",
        "float64 angular_jerk  # of the commanded turn rate, rad^2/s^5",
        "float64 success  # 1/0 for a run, the success rate for several; NaN: unknown",
    ]
)
_TRACKING_TAIL = [_SEP, "MSG: arbiter_msgs/TrackingStats", MCAP_TRACKING_DEF]
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
        "arbiter_msgs/TrackingStats tracking  # against the run's reference path",
        _SEP,
        "MSG: arbiter_msgs/AnalyticsStats",
        MCAP_STATS_DEF,
        *_TRACKING_TAIL,
    ]
)
MCAP_ALGORITHM_DEF = "\n".join(
    [
        "string algorithm",
        "string mission  # empty for manual driving",
        "uint32 runs",
        "uint32 completed",
        "float64 time_s  # mean over completed runs; NaN when none completed",
        "float64 final_error_m  # likewise",
        "arbiter_msgs/AnalyticsStats stats  # over the pooled samples of all its runs on this mission",
        "arbiter_msgs/TrackingStats tracking  # its runs pooled",
        _SEP,
        "MSG: arbiter_msgs/AnalyticsStats",
        MCAP_STATS_DEF,
        *_TRACKING_TAIL,
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
        writer.writerow([*row, "" if p.runId is None else str(p.runId), "1" if p.gap else ""])
    return out.getvalue()


def to_json(
    points: Sequence[DataPoint],
    stats: AnalyticsStats | None = None,
    runs: Sequence[RunSummary] | None = None,
    algorithms: Sequence[AlgorithmSummary] | None = None,
) -> str:
    """The seed's JSON export plus, when given, the run summaries and per-(mission, algorithm) rows (a
    reader tells "no runs" from "not recorded" by the key's presence)."""
    if stats is None:
        stats = stats_of_points(points)
    doc: dict[str, Any] = {"dataPoints": [p.as_dict() for p in points], "stats": stats.as_dict()}
    if runs is not None:
        doc["runs"] = [r.as_dict() for r in runs]
    if algorithms is not None:
        doc["algorithms"] = [a.as_dict() for a in algorithms]
    return json.dumps(doc, allow_nan=False, indent=1) + "\n"


def to_mcap(
    points: Sequence[DataPoint],
    stats: AnalyticsStats | None = None,
    runs: Sequence[RunSummary] | None = None,
    algorithms: Sequence[AlgorithmSummary] | None = None,
) -> bytes:
    if stats is None:
        stats = stats_of_points(points)
    rows = [_mcap_point(p) for p in points]  # validate everything before writing a byte
    stats_row = _mcap_stats(stats)
    run_rows = [_mcap_run(r) for r in runs or ()]
    algorithm_rows = [_mcap_algorithm(a) for a in algorithms or ()]
    buf = io.BytesIO()
    # the summary channels exist when the summaries were given (even none): "no runs", not "unknown"
    channels = McapChannels(buf, runs=runs is not None, algorithms=algorithms is not None)
    last_ns = 0
    for p, row in zip(points, rows, strict=False):
        last_ns = max(last_ns, channels.point(p, row))
    for r, row in zip(runs or (), run_rows, strict=True):
        channels.run(r, row)
    for row in algorithm_rows:
        channels.algorithm(row, last_ns)
    channels.stats(stats_row, last_ns)
    channels.finish()
    return buf.getvalue()


class McapChannels:
    """An export's channels on an MCAP stream (chunked, zstd): one definition of what each channel holds,
    for an export written at once (:func:`to_mcap`) and for the session's journal, written as it goes
    (``session/journal.py``: :meth:`flush` ends the chunk in progress and hands it to the stream)."""

    def __init__(self, stream: IO[bytes], runs: bool = True, algorithms: bool = True) -> None:
        from mcap_ros2.writer import Writer

        self.writer = Writer(stream)
        self._point = self.writer.register_msgdef(MCAP_POINT_TYPE, MCAP_POINT_DEF)
        self._odom = self.writer.register_msgdef(MCAP_ODOM_TYPE, MCAP_ODOM_DEF)
        self._stats = self.writer.register_msgdef(MCAP_STATS_TYPE, MCAP_STATS_DEF)
        self._run = self.writer.register_msgdef(MCAP_RUN_TYPE, MCAP_RUN_DEF) if runs else None
        self._algorithm = (
            self.writer.register_msgdef(MCAP_ALGORITHM_TYPE, MCAP_ALGORITHM_DEF) if algorithms else None
        )
        self._plan: Any = None  # registered with the first plan: an export without plans has no channel

    def point(self, p: DataPoint, row: dict[str, Any] | None = None) -> int:
        """A sample on the data point and odometry channels; its log time (ns)."""
        t_ns = max(0, int(p.timestamp * 1_000_000))
        w, row = self.writer, row or _mcap_point(p)
        w.write_message(MCAP_POINT_TOPIC, self._point, row, log_time=t_ns, publish_time=t_ns)
        w.write_message(MCAP_ODOM_TOPIC, self._odom, _odometry(p, t_ns), log_time=t_ns, publish_time=t_ns)
        return t_ns

    def run(self, r: RunSummary, row: dict[str, Any] | None = None) -> None:
        """A run's summary (a reader keeps the last one of each run id)."""
        if self._run is not None:
            t_ns = max(0, int((r.end_ms if r.end_ms is not None else r.last_ms or r.start_ms) * 1_000_000))
            row = row or _mcap_run(r)
            self.writer.write_message(MCAP_RUNS_TOPIC, self._run, row, log_time=t_ns, publish_time=t_ns)

    def algorithm(self, a: AlgorithmSummary | dict[str, Any], t_ns: int) -> None:
        """A per-(mission, algorithm) row (a reader keeps the last one of each)."""
        if self._algorithm is not None:
            row = a if isinstance(a, dict) else _mcap_algorithm(a)
            topic, schema = MCAP_ALGORITHMS_TOPIC, self._algorithm
            self.writer.write_message(topic, schema, row, log_time=t_ns, publish_time=t_ns)

    def plan(self, run_id: int, t_ms: float, xy: Sequence[Sequence[float]]) -> None:
        """A run's reference path from ``t_ms`` on (``xy``: its positions)."""
        if self._plan is None:
            self._plan = self.writer.register_msgdef(MCAP_PLAN_TYPE, MCAP_PLAN_DEF)
        row = {
            "run_id": run_id,
            "timestamp": t_ms,
            "x": [float(p[0]) for p in xy],
            "y": [float(p[1]) for p in xy],
        }
        t_ns = max(0, int(t_ms * 1_000_000))
        self.writer.write_message(MCAP_PLANS_TOPIC, self._plan, row, log_time=t_ns, publish_time=t_ns)

    def stats(self, s: AnalyticsStats | dict[str, Any], t_ns: int) -> None:
        row = s if isinstance(s, dict) else _mcap_stats(s)
        self.writer.write_message(MCAP_STATS_TOPIC, self._stats, row, log_time=t_ns, publish_time=t_ns)

    def metadata(self, name: str, data: dict[str, str]) -> None:
        self.writer.add_metadata(name, data)

    def flush(self) -> None:
        """The chunk in progress ends and goes to the stream, and the stream is flushed (not synced)."""
        # mcap_ros2's Writer wraps mcap's, whose flush() is public (mcap>=1.2) but not annotated
        self.writer._writer.flush()  # type: ignore[no-untyped-call]

    def finish(self) -> None:
        """The summary and the footer: the file is complete."""
        self.writer.finish()  # type: ignore[no-untyped-call]  # mcap_ros2's Writer.finish is not annotated


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
    # the time and final error as the JSON export rounds them (``RunSummary.rounded``): a run still open
    # has no end, its time is read back from this figure, and the two files must grade it alike
    time_s, final = r.rounded()
    return {
        "id": r.id,
        "algorithm": r.algorithm,
        "mission": r.mission,
        "outcome": r.outcome,
        "completed": r.completed,
        "start_ms": float(r.start_ms),
        "end_ms": math.nan if r.end_ms is None else float(r.end_ms),
        "time_s": float(time_s),
        "final_error_m": math.nan if final is None else float(final),
        "stats": _mcap_stats(r.stats),
        "tracking": _mcap_tracking(r.tracking),
    }


def _mcap_algorithm(a: AlgorithmSummary) -> dict[str, Any]:
    return {
        "algorithm": a.algorithm,
        "mission": a.mission,
        "runs": int(a.runs),
        "completed": int(a.completed),
        "time_s": math.nan if a.time_s is None else float(a.time_s),
        "final_error_m": math.nan if a.final_error_m is None else float(a.final_error_m),
        "stats": _mcap_stats(a.stats),
        "tracking": _mcap_tracking(a.tracking),
    }


def _mcap_tracking(t: TrackingStats | None) -> dict[str, Any]:
    if t is None:
        return {"measured": False, "samples": 0, **{name: 0.0 for name in TRACKING_FIELDS}}
    return {
        "measured": True,
        "samples": t.samples,
        **{name: math.nan if (v := getattr(t, name)) is None else float(v) for name in TRACKING_FIELDS},
    }


def _mcap_tracking_dict(m: Any) -> dict[str, Any] | None:
    """The JSON form (``TrackingStats.as_dict``) of a decoded MCAP tracking field; None when the
    summary has none (or the file predates it)."""
    t = getattr(m, "tracking", None)
    if t is None or not t.measured:
        return None
    # a file written before a field existed has no such attribute: unknown
    values = {name: None if math.isnan(v := getattr(t, name, math.nan)) else v for name in TRACKING_FIELDS}
    return {"samples": t.samples, **values}


def _tracking_from(raw: Any, where: str) -> TrackingStats | None:
    if raw is None:
        return None
    try:
        return TrackingStats.from_dict(raw)
    except ValueError as exc:
        raise ExportFormatError(f"{where}: {exc}") from None


MCAP_MAGIC = b"\x89MCAP0\r\n"


@dataclass(frozen=True)
class Export:
    """What an export file holds: its points and, where the file carries them (JSON and MCAP exports
    since runs exist), the run summaries and per-(mission, algorithm) rows as the console computed them
    over all of their samples, however many of those the file holds."""

    points: list[DataPoint]
    runs: tuple[RunSummary, ...] | None = None
    algorithms: tuple[AlgorithmSummary, ...] | None = None
    notes: tuple[str, ...] = ()  # what the figures cannot vouch for (a journal cut short)
    plans: tuple[Plan, ...] = ()  # each run's reference paths as they came (a journal carries them)


@dataclass(frozen=True)
class Plan:
    """A run's reference path from ``t_ms`` on (the first, and each replan): positions in odometry's frame."""

    run_id: int
    t_ms: float
    xy: tuple[tuple[float, float], ...]


def _opt_number(raw: Any, where: str) -> float | None:
    if raw is None or (isinstance(raw, float) and math.isnan(raw)):
        return None
    if isinstance(raw, bool) or not isinstance(raw, (int, float)) or not math.isfinite(raw):
        raise ExportFormatError(f"{where}: must be a finite number or null")
    return float(raw)


def _stats_from(raw: Any, where: str) -> AnalyticsStats:
    if not isinstance(raw, dict):
        raise ExportFormatError(f"{where}: stats must be an object")
    values: dict[str, float] = {}
    for name in STATS_FIELDS:
        v = _opt_number(raw.get(name), f"{where}.stats.{name}")
        if v is None:
            raise ExportFormatError(f"{where}: stats.{name} missing")
        values[name] = v
    return AnalyticsStats(int(values.pop("sampleCount")), **values)


def _text(raw: Any, where: str) -> str:
    if not isinstance(raw, str):
        raise ExportFormatError(f"{where}: must be a string")
    return raw


def _count(raw: Any, where: str) -> int:
    if isinstance(raw, bool) or not isinstance(raw, int) or raw < 0:
        raise ExportFormatError(f"{where}: must be a whole number")
    return raw


def runs_from(rows: Any, in_file: dict[int, int]) -> tuple[RunSummary, ...]:
    """Run summaries from their JSON form (``RunSummary.as_dict``); ``in_ring`` = samples in the file."""
    if not isinstance(rows, list):
        raise ExportFormatError("runs must be a list")
    out = []
    for i, row in enumerate(rows):
        where = f"runs[{i}]"
        if not isinstance(row, dict):
            raise ExportFormatError(f"{where} must be an object")
        run_id = _run_id(row.get("id"), where)
        if run_id is None:
            raise ExportFormatError(f"{where}: id missing")
        outcome = _text(row.get("outcome"), f"{where}.outcome")
        if outcome not in OUTCOMES:
            raise ExportFormatError(f"{where}: unknown outcome {outcome[:20]!r}")
        start = _opt_number(row.get("start_ms"), f"{where}.start_ms") or 0.0
        end = _opt_number(row.get("end_ms"), f"{where}.end_ms")
        time_s = _opt_number(row.get("time_s"), f"{where}.time_s") or 0.0
        algorithm = _text(row.get("algorithm"), f"{where}.algorithm")
        mission = _text(row.get("mission"), f"{where}.mission")
        final = _opt_number(row.get("final_error_m"), f"{where}.final_error_m")
        stats = _stats_from(row.get("stats"), where)
        last = start + time_s * 1000.0
        in_ring = in_file.get(run_id, 0)
        tracking = _tracking_from(row.get("tracking"), where)
        out.append(
            RunSummary(run_id, algorithm, mission, start, end, outcome, final, stats, in_ring, last, tracking)
        )
    return tuple(out)


def algorithms_from(rows: Any) -> tuple[AlgorithmSummary, ...]:
    """Per-(mission, algorithm) rows from their JSON form (``AlgorithmSummary.as_dict``)."""
    if not isinstance(rows, list):
        raise ExportFormatError("algorithms must be a list")
    out = []
    for i, row in enumerate(rows):
        where = f"algorithms[{i}]"
        if not isinstance(row, dict):
            raise ExportFormatError(f"{where} must be an object")
        out.append(
            AlgorithmSummary(
                algorithm=_text(row.get("algorithm"), f"{where}.algorithm"),
                mission=_text(row.get("mission"), f"{where}.mission"),
                runs=_count(row.get("runs"), f"{where}.runs"),
                completed=_count(row.get("completed"), f"{where}.completed"),
                time_s=_opt_number(row.get("time_s"), f"{where}.time_s"),
                final_error_m=_opt_number(row.get("final_error_m"), f"{where}.final_error_m"),
                stats=_stats_from(row.get("stats"), where),
                tracking=_tracking_from(row.get("tracking"), where),
            )
        )
    return tuple(out)


def samples_per_run(points: Sequence[DataPoint]) -> dict[int, int]:
    counts: dict[int, int] = {}
    for p in points:
        if p.runId is not None:
            counts[p.runId] = counts.get(p.runId, 0) + 1
    return counts


_MCAP_STATS_NAMES = ("sample_count", *(line.split()[1] for line in MCAP_STATS_DEF.split("\n")[1:]))


def _mcap_stats_dict(m: Any) -> dict[str, Any]:
    return {name: getattr(m, mcap) for name, mcap in zip(STATS_FIELDS, _MCAP_STATS_NAMES, strict=True)}


def parse_mcap(data: bytes) -> list[DataPoint]:
    """The DataPoints of an MCAP export (the ``/arbiter/data_point`` channel; other channels ignored)."""
    return read_mcap(data).points


NOT_ARBITER_MCAP = "MCAP, but not an arbiter analytics export"


JOURNAL_METADATA = "arbiter_journal"  # the metadata record that makes an MCAP a session's journal
JOURNAL_END_METADATA = "arbiter_journal_end"  # written when the session ends: how it ended


def read_mcap(data: bytes) -> Export:
    """An MCAP export: its DataPoints, and the run and algorithm summaries where it has those channels
    (a run or a row written more than once, as a journal writes them while they change: the last one).
    A session's journal cut short (the console killed, the power lost: no summary, no footer) is read up
    to where it stops, and says so in ``notes``. A damaged or foreign file is an ``ExportFormatError``
    that says which: ``truncated MCAP: …``, ``corrupt MCAP: …``, ``MCAP, but not an arbiter analytics
    export: …``, ``bad arbiter MCAP export: …``."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    if not data.startswith(MCAP_MAGIC):
        raise ExportFormatError("not an MCAP file")
    if len(data) < 2 * len(MCAP_MAGIC) or not data.endswith(MCAP_MAGIC):
        recovered = recover_journal(data)
        if recovered is None:
            # a finished MCAP ends with its magic after the footer; the reader would report some length it
            # read from wherever the file stops
            what = "no end marker (cut short, or its writer never finished)"
            raise ExportFormatError(f"truncated MCAP: {len(data)} bytes and {what}")
        messages, note = recovered
        return _collect(messages, lambda: None, notes=(note,))
    try:
        reader = make_reader(io.BytesIO(data), decoder_factories=[DecoderFactory()])
        decoded = ((c.topic, m) for _s, c, _msg, m in reader.iter_decoded_messages(topics=list(_READ_TOPICS)))
        return _collect(decoded, reader.get_summary)
    except ExportFormatError:
        raise
    except Exception as exc:  # the reader raises McapError, struct.error, KeyError, EOFError,
        # ValueError... on a damaged file: every one of them means "damaged", none a traceback
        raise ExportFormatError(f"corrupt MCAP: {str(exc) or type(exc).__name__}") from None


_READ_TOPICS = (MCAP_POINT_TOPIC, MCAP_RUNS_TOPIC, MCAP_ALGORITHMS_TOPIC, MCAP_PLANS_TOPIC)


def recover_journal(data: bytes) -> tuple[list[tuple[str, Any]], str] | None:
    """A session's journal without its end (``JOURNAL_METADATA`` in it): its messages on the topics read,
    decoded, up to the last whole chunk, and a note saying so; None when ``data`` is not a journal."""
    from mcap.records import Channel, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader
    from mcap_ros2.decoder import DecoderFactory

    factory = DecoderFactory()
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    decoders: dict[int, Any] = {}
    out: list[tuple[str, Any]] = []
    journal = False
    try:
        for record in StreamReader(io.BytesIO(data), skip_magic=False).records:
            if isinstance(record, Metadata) and record.name == JOURNAL_METADATA:
                journal = True
            elif isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message):
                channel = channels.get(record.channel_id)
                if channel is None or channel.topic not in _READ_TOPICS:
                    continue
                if record.channel_id not in decoders:
                    schema = schemas[channel.schema_id]
                    decoders[record.channel_id] = factory.decoder_for(channel.message_encoding, schema)
                out.append((channel.topic, decoders[record.channel_id](record.data)))
    except Exception:  # where the file stops: inside a record, a chunk cut short
        pass
    if not journal:
        return None
    samples = sum(topic == MCAP_POINT_TOPIC for topic, _ in out)
    note = (
        f"a journal cut short ({len(data)} bytes, no end: the console was killed or lost power): "
        f"{samples} samples read, up to its last flush"
    )
    return out, note


def _collect(messages: Iterable[tuple[str, Any]], summary: Any, notes: tuple[str, ...] = ()) -> Export:
    """The points, runs and per-algorithm rows of an MCAP's decoded ``(topic, message)`` pairs."""
    points: list[DataPoint] = []
    runs: dict[int, dict[str, Any]] = {}
    algorithms: dict[tuple[str, str], dict[str, Any]] = {}
    plans: list[Plan] = []
    seen: set[str] = set()
    topic = ""
    try:
        for topic, m in messages:
            seen.add(topic)
            if topic == MCAP_RUNS_TOPIC:
                runs[m.id] = {
                    "id": m.id, "algorithm": m.algorithm, "mission": m.mission, "outcome": m.outcome,
                    "start_ms": m.start_ms, "end_ms": m.end_ms, "time_s": m.time_s,
                    "final_error_m": m.final_error_m, "stats": _mcap_stats_dict(m.stats),
                    "tracking": _mcap_tracking_dict(m),
                }  # fmt: skip
                continue
            if topic == MCAP_PLANS_TOPIC:
                xy = tuple(zip(map(float, m.x), map(float, m.y), strict=True))
                plans.append(Plan(int(m.run_id), float(m.timestamp), xy))
                continue
            if topic == MCAP_ALGORITHMS_TOPIC:
                algorithms[(m.mission, m.algorithm)] = {
                    "algorithm": m.algorithm, "mission": m.mission, "runs": m.runs, "completed": m.completed,
                    "time_s": m.time_s, "final_error_m": m.final_error_m, "stats": _mcap_stats_dict(m.stats),
                    "tracking": _mcap_tracking_dict(m),
                }  # fmt: skip
                continue
            points.append(_point_from_message(m, f"MCAP message {len(points) + 1}"))
        if not seen:
            found = summary()
            channels = sorted({c.topic for c in found.channels.values()}) if found else []
            if not any(t.startswith("/arbiter/") for t in channels):
                named = ", ".join(channels[:5]) + (", …" if len(channels) > 5 else "")
                has = f"its topics: {named}" if channels else "it has no channels"
                raise ExportFormatError(f"{NOT_ARBITER_MCAP}: no {MCAP_POINT_TOPIC} channel ({has})")
        return Export(
            points,
            runs_from(list(runs.values()), samples_per_run(points)) if MCAP_RUNS_TOPIC in seen else None,
            algorithms_from(list(algorithms.values())) if MCAP_ALGORITHMS_TOPIC in seen else None,
            notes,
            tuple(plans),
        )
    except ExportFormatError as exc:
        if str(exc).startswith(NOT_ARBITER_MCAP):
            raise
        raise ExportFormatError(f"bad arbiter MCAP export: {exc}") from None
    except AttributeError as exc:  # a message on one of our topics without our fields
        field = f" {exc.name!r}" if getattr(exc, "name", None) else ""
        raise ExportFormatError(f"{NOT_ARBITER_MCAP}: its {topic} messages have no field{field}") from None


def _point_from_message(m: Any, where: str) -> DataPoint:
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
        "gap": bool(getattr(m, "gap", False)),  # nor before gaps
    }
    return _point_from_mapping(row, where)


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
        "gap": p.gap,
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
    return DataPoint(**values, runId=_run_id(row.get("runId"), where), gap=_gap(row.get("gap"), where))


def _gap(raw: Any, where: str) -> bool:
    """``gap``: true/false (JSON, MCAP), ``1`` or empty (CSV); absent in exports from before it."""
    if raw is None or raw == "" or raw is False or raw == "0":
        return False
    if raw is True or raw == "1":
        return True
    raise ExportFormatError(f"{where}: gap must be true, false, 1 or empty, got {str(raw)[:40]!r}")


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


NOT_ARBITER_CSV = "CSV, but not an arbiter analytics export"


def parse_csv(text: str) -> list[DataPoint]:
    """The points of a CSV export (ours, or the seed's ten columns). What is wrong is said with what the
    file is: ``empty file``, ``CSV, but not an arbiter analytics export: …``, ``truncated CSV: …``,
    ``bad arbiter CSV export: line N: …``."""
    lines = text.splitlines()
    if not lines or not text.strip():
        raise ExportFormatError("empty file")
    header = lines[0].strip().lstrip("\ufeff")
    if header not in CSV_HEADERS:
        first = header[:60] + ("…" if len(header) > 60 else "")
        if "," not in header:
            raise ExportFormatError(f"text, but not a CSV, JSON or MCAP export: its first line is {first!r}")
        raise ExportFormatError(
            f"{NOT_ARBITER_CSV}: its header is {first!r}; an export's is {CSV_HEADER!r} (the seed's: without "
            "runId and gap)"
        )
    columns = header.count(",") + 1
    reader = csv.DictReader(io.StringIO(text.lstrip("\ufeff")))
    points = []
    i = 1
    try:
        for i, row in enumerate(reader, start=2):
            if None in row or any(v is None for v in row.values()):
                given = sum(v is not None for k, v in row.items() if k is not None)
                if i == len(lines) and not text.endswith(("\n", "\r")) and None not in row:
                    raise ExportFormatError(
                        f"truncated CSV: its last line ({i}) stops after {given} of {columns} columns"
                    )
                raise ExportFormatError(f"bad arbiter CSV export: line {i}: expected {columns} columns")
            try:
                points.append(_point_from_mapping(row, f"line {i}"))
            except ExportFormatError as exc:
                raise ExportFormatError(f"bad arbiter CSV export: {exc}") from None
    except csv.Error as exc:  # a field over the csv module's size limit, a stray quote...
        raise ExportFormatError(f"bad arbiter CSV export: line {i + 1}: {exc}") from None
    return points


def parse_json(text: str) -> list[DataPoint]:
    return read_json(text).points


NOT_ARBITER_JSON = "JSON, but not an arbiter analytics export"


def _json_kind(value: Any) -> str:
    if isinstance(value, list):
        return "a list" if value else "an empty list"
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, str):
        return "a string"
    if value is None:
        return "null"
    return "true/false" if isinstance(value, bool) else "a number"


def read_json(text: str) -> Export:
    """A JSON export. What is wrong is said with what the file is: ``truncated JSON: …``, ``invalid
    JSON: …``, ``JSON, but not an arbiter analytics export: …``, ``bad arbiter JSON export: …``."""

    def reject(token: str) -> Any:
        raise ExportFormatError(f"non-standard JSON token {token} (an export is strict JSON)")

    try:
        doc = json.loads(text, parse_constant=reject)
    except ExportFormatError:
        raise
    except json.JSONDecodeError as exc:
        # the text ran out inside the document (a string with no closing quote runs to the end too)
        if exc.pos >= len(text.rstrip()) or exc.msg.startswith("Unterminated string"):
            raise ExportFormatError(
                f"truncated JSON: it ends at line {exc.lineno} column {exc.colno} inside the document"
            ) from None
        raise ExportFormatError(f"invalid JSON: {exc}") from None
    except (ValueError, RecursionError) as exc:
        raise ExportFormatError(f"invalid JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise ExportFormatError(
            f'{NOT_ARBITER_JSON}: the top level is {_json_kind(doc)}, not an object {{"dataPoints": [...]}}'
        )
    if "dataPoints" not in doc:
        keys = ", ".join(repr(k)[:30] for k in list(doc)[:5]) + (", …" if len(doc) > 5 else "")
        has = f"its keys: {keys}" if doc else "an empty object"
        raise ExportFormatError(f'{NOT_ARBITER_JSON}: no "dataPoints" ({has})')
    if not isinstance(doc["dataPoints"], list):
        raise ExportFormatError(
            f'{NOT_ARBITER_JSON}: "dataPoints" is {_json_kind(doc["dataPoints"])}, not a list'
        )
    try:
        out = []
        for i, row in enumerate(doc["dataPoints"]):
            if not isinstance(row, dict):
                raise ExportFormatError(f"dataPoints[{i}] must be an object")
            out.append(_point_from_mapping(row, f"dataPoints[{i}]"))
        runs = runs_from(doc["runs"], samples_per_run(out)) if "runs" in doc else None
        algorithms = algorithms_from(doc["algorithms"]) if "algorithms" in doc else None
    except ExportFormatError as exc:
        raise ExportFormatError(f"bad arbiter JSON export: {exc}") from None
    return Export(out, runs, algorithms)


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
