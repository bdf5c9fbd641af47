"""Recorded ``ros2 bag``s as runs: ``arbiter-tui stats BAG``.

What is read (docs/analytics.md): a rosbag2 directory (``metadata.yaml``: MCAP or SQLite 3
storage, split into several files or not, zstd file or message compression), a lone storage file as it
is shared (``.mcap`` or ``.db3``), or a directory of storage files whose ``metadata.yaml`` is missing (a
recorder killed before it wrote one), read from its files with a note. The files are opened with the
``rosbags`` library's storage readers (pure Python: no ROS install), and only the connections graded
here are looked at: only their message definitions are parsed (a bag that also holds topics of types
nobody here can parse, service events say, still grades), and only what becomes a sample is decoded:
odometry at the collection rate, the latest command before it, every plan (its positions straight from
the bytes: ``cdr.path_xy``), goal and action status, and each scan's nearest obstacle. Messages go, in
log-time order, through the same :class:`observe.Observer` as a live observation, into an
:class:`AnalyticsStore` large enough to keep every sample.

Every refusal is one :class:`ExportFormatError` line naming the file, what it is, what is wrong and
what to run; running out of memory is :class:`OutOfMemory`, never a damaged file.
"""

from __future__ import annotations

import functools
import heapq
import re
import tempfile
from collections.abc import Callable, Iterator
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from arbiter_core.kinematics import quaternion_to_yaw

from .cdr import path_xy
from .exports import MCAP_MAGIC, MCAP_POINT_TOPIC, Export, ExportFormatError
from .observe import ObserveConfig, Observer
from .scorecards import Scans, nearest_obstacle
from .store import AnalyticsStore

if TYPE_CHECKING:
    from rosbags.rosbag2.reader import DirectoryReader

MAX_SAMPLES = 1_000_000  # the store's largest ring: a day at 10 Hz
ODOMETRY = "nav_msgs/msg/Odometry"
TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
PATH = "nav_msgs/msg/Path"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
GOAL_STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
SQLITE_MAGIC = b"SQLite format 3\0"
ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"
STORAGE_SUFFIXES = (".mcap", ".db3")
EXPORT_LIBRARY = "mcap-ros2-support"  # what writes arbiter's MCAP exports (exports.to_mcap)
SNIFF_RECORDS = 10_000  # an MCAP with no summary: records read from its start for its channels


@dataclass(frozen=True, slots=True)
class BagTopics:
    odom: str = "/odom"
    cmd: str = "/cmd_vel"
    plan: str = "/plan"
    goal: str = "/goal_pose"
    status: str = "/navigate_to_pose/_action/status"  # action_msgs/GoalStatusArray of Nav2's navigator
    scan: str = "/scan"


DEFAULT_TOPICS = BagTopics()
DEFAULT_CONFIG = ObserveConfig()


class OutOfMemory(ExportFormatError):
    """Reading the bag needed more memory than there is: the file is not damaged."""


@dataclass(frozen=True, slots=True)
class Recording:
    """A bag's runs and samples (an :class:`Export`), its scans' nearest obstacles, and what it was."""

    export: Export
    scans: Scans | None  # None: no scan topic in the bag
    what: str  # e.g. "ros2 bag directory (mcap, 3 files)"


# -- what a path is ----------------------------------------------------------------------------------


def bag_kind(path: Path) -> str | None:
    """What ``path`` is as a rosbag2 recording (``ros2 bag directory``, ``ros2 bag MCAP file``...), or
    None when it is not one (an arbiter export, anything else)."""
    path = Path(path)
    try:
        if path.name == "metadata.yaml" and path.is_file():
            return "ros2 bag directory"
        if path.is_dir():
            if (path / "metadata.yaml").is_file():
                return "ros2 bag directory"
            return "ros2 bag directory without metadata.yaml" if storage_files(path) else None
        if not path.is_file():
            return None
        with path.open("rb") as fh:
            head = fh.read(len(SQLITE_MAGIC))
    except OSError:
        return None
    if head.startswith(SQLITE_MAGIC):
        return "ros2 bag SQLite 3 file"
    if head.startswith(MCAP_MAGIC) and not _is_arbiter_mcap(path):
        return "ros2 bag MCAP file"
    return None


def is_bag(path: Path) -> bool:
    return bag_kind(path) is not None


def storage_files(directory: Path) -> list[Path]:
    """A bag directory's storage files in split order (``…_0.mcap``, ``…_1.mcap``; ``.zstd`` compressed
    ones too), by the number before the suffix."""

    def split_index(p: Path) -> tuple[int, str]:
        m = re.search(r"_(\d+)\.(?:mcap|db3)(?:\.zstd)?$", p.name)
        return (int(m.group(1)) if m else -1, p.name)

    files = [
        p
        for p in directory.iterdir()
        if p.is_file() and p.name.endswith(tuple(s + z for s in STORAGE_SUFFIXES for z in ("", ".zstd")))
    ]
    return sorted(files, key=split_index)


def _is_arbiter_mcap(path: Path) -> bool:
    """Whether an MCAP file is (or, cut short, was meant to be) an arbiter analytics export rather than a
    ros2 bag: its channels include our data point channel, or are all ours (from its summary; with none,
    from the channel records before its first message); where no channel can be read (cut inside its
    first chunk), its header's library says: arbiter writes exports with ``mcap-ros2-support``, recorders
    do not."""
    from mcap.reader import make_reader
    from mcap.records import Channel, Header, Message
    from mcap.stream_reader import StreamReader

    try:
        with path.open("rb") as fh:
            summary = make_reader(fh).get_summary()
        if summary is not None:
            return _ours({c.topic for c in summary.channels.values()})
    except Exception:  # no footer, or a damaged one: read from the start
        pass
    topics: set[str] = set()
    library = None
    with path.open("rb") as fh:
        try:
            for n, record in enumerate(StreamReader(fh, skip_magic=False).records):
                if isinstance(record, Header):
                    library = record.library
                elif isinstance(record, Channel):
                    topics.add(record.topic)
                elif isinstance(record, Message) or n > SNIFF_RECORDS:
                    break
        except Exception:  # cut short: what was read before the cut decides
            pass
    if topics:
        return _ours(topics)
    return library is None or EXPORT_LIBRARY in library


def _ours(topics: set[str]) -> bool:
    """An export's channels: the data points, or (an export of no samples) only its other /arbiter/ ones."""
    return MCAP_POINT_TOPIC in topics or (bool(topics) and all(t.startswith("/arbiter/") for t in topics))


# -- reading -----------------------------------------------------------------------------------------


def read_bag(
    path: Path,
    topics: BagTopics = DEFAULT_TOPICS,
    config: ObserveConfig = DEFAULT_CONFIG,
    warn: Callable[[str], None] = lambda text: None,
) -> Recording:
    """The bag's runs and samples; ExportFormatError with one line saying what is wrong (see the module),
    OutOfMemory when there was not enough. ``warn``: what the figures cannot vouch for (frames that
    differ, stamps from another clock, a missing metadata.yaml), each once."""
    path = Path(path)
    if path.name == "metadata.yaml":
        path = path.parent
    kind = bag_kind(path)
    if kind is None:
        raise ExportFormatError(f"{path} is not a ros2 bag (no metadata.yaml, .mcap or .db3 storage file)")
    try:
        return _read(path, kind, topics, config, warn)
    except ExportFormatError:
        raise
    except MemoryError:
        raise OutOfMemory(
            f"out of memory reading {kind} {path}: the file is not damaged, this machine has too little "
            "free memory for it (close other programs, or grade it on a larger machine)"
        ) from None
    except Exception as exc:  # rosbags' own errors, and what a damaged file makes its decoders raise
        raise ExportFormatError(_refusal(path, kind, exc)) from None


def _read(
    path: Path, kind: str, topics: BagTopics, config: ObserveConfig, warn: Callable[[str], None]
) -> Recording:
    from rosbags.rosbag2 import Reader

    with ExitStack() as stack:
        if kind == "ros2 bag directory":
            bag = Reader(path)
            bag.open()
            stack.callback(bag.close)
            storages: list[Any] = [bag]
            directory = cast("DirectoryReader", bag.storage)  # the Reader of a directory reads it with one
            what = f"{kind} ({_describe(directory.storages, bag.compression_mode)})"
            message_zstd = False
        else:
            files_ = [path] if path.is_file() else storage_files(path)
            storages = [_open_storage(f, stack) for f in files_]
            what = kind if path.is_file() else f"{kind} ({_describe(storages, None)})"
            if path.is_dir():
                warn(
                    f"no metadata.yaml (its recorder stopped before writing it): read from its {len(files_)} "
                    f"storage file{'s' * (len(files_) != 1)}; `ros2 bag reindex {path}` writes it"
                )
            message_zstd = True  # no metadata says whether messages are compressed: each one says so
        return _grade(storages, path, what, topics, config, warn, message_zstd)


def _describe(storages: list[Any], compression: str | None) -> str:
    """``MCAP, 3 files, zstd message compression``."""
    names = sorted({"SQLite 3" if type(s).__name__.startswith("Sqlite") else "MCAP" for s in storages})
    n = len(storages)
    zstd = f", zstd {compression} compression" if compression else ""
    return f"{' and '.join(names)}, {n} file{'s' * (n != 1)}{zstd}"


def _open_storage(file: Path, stack: ExitStack) -> Any:
    """One storage file, opened (a ``.zstd`` one decompressed to a temporary file first)."""
    from rosbags.rosbag2.storage_mcap import McapReader
    from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

    if file.name.endswith(".zstd"):
        import shutil

        zstd = _zstd()
        tmp = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="arbiter-bag-")))
        plain = tmp / file.name.removesuffix(".zstd")
        with file.open("rb") as src, zstd.open(src, "rb") as unz, plain.open("wb") as dst:
            shutil.copyfileobj(unz, dst)
        file = plain
    with file.open("rb") as fh:
        head = fh.read(len(SQLITE_MAGIC))
    storage = Sqlite3Reader(file) if head.startswith(SQLITE_MAGIC) else McapReader(file)
    storage.open()
    stack.callback(storage.close)
    return storage


class _Decoder:
    """Deserialises the graded connections only: their own message definitions where the bag has them
    (parsed here, one topic at a time), else the ROS 2 definitions rosbags ships."""

    def __init__(self, connections: list[Any]) -> None:
        from rosbags.interfaces import MessageDefinitionFormat
        from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore

        self.default = get_typestore(Stores.ROS2_KILTED)
        types: dict[str, Any] = {}
        for conn in connections:
            fmt, data = conn.msgdef.format, conn.msgdef.data
            if fmt == MessageDefinitionFormat.NONE or conn.msgtype in types:
                continue
            try:
                if fmt == MessageDefinitionFormat.MSG:
                    types.update(get_types_from_msg(data, conn.msgtype))
                else:
                    sep = "=" * 80 + "\n"
                    for part in data.split(sep)[1:] if data.startswith(f"{sep}IDL: ") else [data]:
                        types.update(
                            get_types_from_idl(part.split("\n", 1)[1] if part.startswith("IDL: ") else part)
                        )
            except Exception as exc:
                why = _first(exc)
                raise ExportFormatError(
                    f"ros2 bag topic {conn.topic}: its {conn.msgtype} definition does not parse ({why})"
                ) from None
        self.bag = get_typestore(Stores.EMPTY)
        if types:
            self.bag.register(types)

    def __call__(self, raw: bytes | memoryview, msgtype: str) -> Any:
        store = self.bag if msgtype in self.bag.fielddefs else self.default
        return store.deserialize_cdr(raw, msgtype)


def _grade(
    storages: list[Any],
    path: Path,
    what: str,
    topics: BagTopics,
    config: ObserveConfig,
    warn: Callable[[str], None],
    message_zstd: bool,
) -> Recording:
    by_topic: dict[str, list[Any]] = {}
    for storage in storages:
        for conn in storage.connections:
            by_topic.setdefault(conn.topic, []).append((storage, conn))
    if topics.odom not in by_topic:
        have = ", ".join(sorted(by_topic)) or "no topics"
        if what == "ros2 bag MCAP file":  # a lone MCAP: an export or a bag, by what it holds
            raise ExportFormatError(
                f"MCAP, but neither an arbiter analytics export (no {MCAP_POINT_TOPIC} channel) nor a ros2 "
                f"bag with odometry on {topics.odom} (its topics: {have}): see --odom-topic"
            )
        raise ExportFormatError(
            f"{what} {path} has no odometry on {topics.odom} (it has {have}): see --odom-topic"
        )
    roles = (
        (topics.odom, (ODOMETRY,)),
        (topics.cmd, (TWIST, TWIST_STAMPED)),
        (topics.plan, (PATH,)),
        (topics.goal, (POSE_STAMPED,)),
        (topics.status, (GOAL_STATUS_ARRAY,)),
        (topics.scan, (LASER_SCAN,)),
    )
    wanted: list[tuple[Any, Any]] = []
    for topic, types in roles:
        for storage, conn in by_topic.get(topic, ()):
            if conn.msgtype not in types:
                raise ExportFormatError(
                    f"ros2 bag topic {topic} is {conn.msgtype}, not {' or '.join(types)} ({what} {path})"
                )
            if all(c is not conn for _s, c in wanted):
                wanted.append((storage, conn))
    decode = _Decoder([c for _s, c in wanted])
    store = AnalyticsStore(max_data_points=MAX_SAMPLES, collection_rate=config.rate_hz)
    store.start_collection()
    observer = Observer(store, config)
    frames: dict[str, str] = {}  # each topic's header.frame_id, as first seen
    scan_t: list[float] = []
    scan_d: list[float] = []
    odometry_messages = 0
    pending_cmd: tuple[Any, int, bytes] | None = None  # the latest command, decoded when sampled
    for conn, t_ns, raw in _messages(storages, wanted):
        if message_zstd and bytes(raw[:4]) == ZSTD_MAGIC:
            raw = _unzstd(raw)
        topic = conn.topic
        if topic == topics.odom:
            odometry_messages += 1
            if not observer.wants_odometry(t_ns):
                continue
            if pending_cmd is not None:
                _command(observer, decode, *pending_cmd)
                pending_cmd = None
            msg = decode(raw, conn.msgtype)
            frames.setdefault(topic, msg.header.frame_id)
            _odometry(observer, t_ns, msg)
        elif topic == topics.cmd:
            pending_cmd = (conn, t_ns, raw)
        elif topic == topics.plan:
            xy = path_xy(raw)
            if xy is None:  # not the regular layout: the general decoder
                msg = decode(raw, conn.msgtype)
                xy = np.array([(p.pose.position.x, p.pose.position.y) for p in msg.poses]).reshape(-1, 2)
                frames.setdefault(topic, msg.header.frame_id)
            elif topic not in frames:
                frames[topic] = decode(raw, conn.msgtype).header.frame_id
            observer.on_plan(t_ns, xy)
        elif topic == topics.goal:
            msg = decode(raw, conn.msgtype)
            frames.setdefault(topic, msg.header.frame_id)
            observer.on_goal(t_ns, msg.pose.position.x, msg.pose.position.y)
        elif topic == topics.status:
            msg = decode(raw, conn.msgtype)
            observer.on_goal_status(
                t_ns, [(bytes(s.goal_info.goal_id.uuid).hex(), int(s.status)) for s in msg.status_list]
            )
        else:
            msg = decode(raw, conn.msgtype)
            scan_t.append(t_ns / 1e6)
            scan_d.append(nearest_obstacle(msg.ranges, msg.range_min, msg.range_max))
    if not odometry_messages:
        raise ExportFormatError(
            f"{what} {path} has no messages on {topics.odom} (the topic is there, empty): nothing to grade"
        )
    observer.finish()
    _warn_frames(frames, topics.odom, warn)
    if observer.foreign_stamps:
        warn(
            f"{observer.foreign_stamps} stamped commands carry another clock's stamp (over a minute off the "
            "recording's: use_sim_time?): no latency taken from them"
        )
    scans = (
        Scans(topics.scan, np.asarray(scan_t), np.asarray(scan_d, dtype=np.float64))
        if topics.scan in by_topic
        else None
    )
    return Recording(Export(store.points(), store.runs(), store.runs_by_algorithm()), scans, what)


def _messages(storages: list[Any], wanted: list[tuple[Any, Any]]) -> Iterator[tuple[Any, int, bytes]]:
    """The wanted connections' messages of every storage, merged in log-time order."""
    streams = []
    for storage in storages:
        mine = [c for s, c in wanted if s is storage]
        if mine:
            streams.append(storage.messages(mine))
    return (
        heapq.merge(*streams, key=lambda m: m[1]) if len(streams) > 1 else iter(streams[0] if streams else ())
    )


@functools.cache
def _zstd() -> Any:
    """The zstd module: the standard library's from Python 3.14, else rosbags' dependency. Looked up
    once: a failed import is not cached by Python, and messages are decompressed one by one."""
    try:
        from compression import zstd
    except ImportError:
        from backports import zstd
    return zstd


def _unzstd(raw: bytes | memoryview) -> bytes:
    plain: bytes = _zstd().decompress(bytes(raw))
    return plain


def _warn_frames(frames: dict[str, str], odom: str, warn: Callable[[str], None]) -> None:
    """One warning for every topic whose frame is not the odometry's."""
    odom_frame = frames.get(odom)
    by_frame: dict[str, list[str]] = {}
    for topic, frame in sorted(frames.items()):
        if topic != odom and frame and odom_frame and frame != odom_frame:
            by_frame.setdefault(frame, []).append(topic)
    for frame, names in by_frame.items():
        which = " and ".join(names)
        verb = "is" if len(names) == 1 else "are"
        warn(
            f"{which} {verb} in frame '{frame}', odometry in '{odom_frame}': errors and cross-track figures "
            "take the two as one (true while the robot's odometry has not drifted from the map)"
        )


def _odometry(observer: Observer, t_ns: int, msg: Any) -> None:
    p = msg.pose.pose
    q = p.orientation
    theta = quaternion_to_yaw({"x": q.x, "y": q.y, "z": q.z, "w": q.w})
    tw = msg.twist.twist
    observer.on_odometry(t_ns, p.position.x, p.position.y, theta, tw.linear.x, tw.angular.z)


def _command(observer: Observer, decode: _Decoder, conn: Any, t_ns: int, raw: bytes) -> None:
    msg = decode(raw, conn.msgtype)
    if conn.msgtype == TWIST_STAMPED:
        stamp = msg.header.stamp
        stamp_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
        observer.on_command(t_ns, msg.twist.linear.x, msg.twist.angular.z, stamp_ns if stamp_ns > 0 else None)
    else:
        observer.on_command(t_ns, msg.linear.x, msg.angular.z)


# -- saying what is wrong ----------------------------------------------------------------------------


def _first(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    return text if len(text) <= 200 else text[:197] + "…"


def _unfinished_mcap(path: Path) -> Path | None:
    """The first MCAP storage file under ``path`` that does not end with MCAP's magic (cut short)."""
    files = [f for f in ([path] if path.is_file() else storage_files(path)) if f.suffix == ".mcap"]
    for f in files:
        with f.open("rb") as fh:
            fh.seek(0, 2)
            if fh.tell() < 2 * len(MCAP_MAGIC):
                return f
            fh.seek(-len(MCAP_MAGIC), 2)
            if fh.read() != MCAP_MAGIC:
                return f
    return None


def _refusal(path: Path, kind: str, exc: BaseException) -> str:
    """One line: the file, what it is, what is wrong and what to run."""
    reason = _first(exc)
    directory = path if path.is_dir() else path.parent
    reindex = f"`ros2 bag reindex {directory}`"
    cut = _unfinished_mcap(path)
    if cut is not None:
        fixed = cut.with_suffix(".recovered.mcap").name
        then = "" if path.is_file() else f", move the original aside, then {reindex}"
        return (
            f"truncated MCAP storage file {cut} of a {kind} (no end marker: its recorder stopped before "
            f"closing it): run `mcap recover {cut} -o {fixed}`{then}"
        )
    lowered = reason.lower()
    if "serialization format" in lowered:
        return (
            f"{kind} {path} stores messages in a serialization other than CDR ({reason}): only CDR, what "
            "ROS 2 records by default, is read; record again without --serialization-format"
        )
    if "metadata" in lowered or "yaml" in lowered or "database files are missing" in lowered:
        return f"{kind} {path}: its metadata.yaml is wrong ({reason}): run {reindex} to rewrite it"
    if isinstance(exc, FileNotFoundError):
        return f"{kind} {path}: a file it needs is missing ({reason}): run {reindex}"
    if "database" in lowered or "sqlite" in lowered or "malformed" in lowered:
        return (
            f"damaged or unreadable ros2 bag {path} ({kind}, SQLite 3: {reason}): try `sqlite3 FILE.db3 "
            f'".recover" | sqlite3 recovered.db3`, then {reindex}'
        )
    return (
        f"damaged or unreadable ros2 bag {path} ({kind}: {reason}): try {reindex} (MCAP: `mcap doctor FILE`)"
    )
