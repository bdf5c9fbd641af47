"""Recorded ``ros2 bag``s as runs: ``arbiter-tui stats BAG_DIR``.

A rosbag2 recording (a directory with ``metadata.yaml``, MCAP or SQLite 3 storage) is read with the
``rosbags`` library (pure Python: no ROS install), its messages in log-time order through the same
:class:`observe.Observer` as a live observation, into an :class:`AnalyticsStore` large enough to keep
every sample. Only what becomes a sample is decoded: odometry at the collection rate, the latest command
before it, every plan and goal. ``ros2 bag record /odom /cmd_vel /plan /goal_pose`` on the robot is the
recording this expects (topic names are options).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from arbiter_core.kinematics import quaternion_to_yaw

from .exports import Export, ExportFormatError
from .observe import ObserveConfig, Observer
from .store import AnalyticsStore

MAX_SAMPLES = 1_000_000  # the store's largest ring: a day at 10 Hz
ODOMETRY = "nav_msgs/msg/Odometry"
TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
PATH = "nav_msgs/msg/Path"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"


@dataclass(frozen=True, slots=True)
class BagTopics:
    odom: str = "/odom"
    cmd: str = "/cmd_vel"
    plan: str = "/plan"
    goal: str = "/goal_pose"


def is_bag(path: Path) -> bool:
    """A rosbag2 directory (its ``metadata.yaml``), or the metadata file itself."""
    path = Path(path)
    return (path.is_dir() and (path / "metadata.yaml").is_file()) or path.name == "metadata.yaml"


DEFAULT_TOPICS = BagTopics()
DEFAULT_CONFIG = ObserveConfig()


def read_bag(
    path: Path,
    topics: BagTopics = DEFAULT_TOPICS,
    config: ObserveConfig = DEFAULT_CONFIG,
    warn: Callable[[str], None] = lambda text: None,
) -> Export:
    """The bag's runs and samples as an :class:`Export` (points and run summaries); ExportFormatError
    with one line saying what is wrong (not a bag, damaged, no odometry). ``warn``: what the figures
    cannot vouch for (frames that differ, stamps from another clock), once each."""
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise ExportFormatError("reading a ros2 bag needs the rosbags package: pip install rosbags") from None
    path = Path(path)
    if path.name == "metadata.yaml":
        path = path.parent
    store = AnalyticsStore(max_data_points=MAX_SAMPLES, collection_rate=config.rate_hz)
    store.start_collection()
    observer = Observer(store, config)
    try:
        with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_KILTED)) as reader:
            by_topic = {c.topic: c for c in reader.connections}
            odom = by_topic.get(topics.odom)
            if odom is None:
                have = ", ".join(sorted(by_topic)) or "no topics"
                raise ExportFormatError(
                    f"ros2 bag without odometry on {topics.odom} (it has {have}): see --odom-topic"
                )
            _check_type(odom, (ODOMETRY,))
            wanted = [odom]
            for name, types in (
                (topics.cmd, (TWIST, TWIST_STAMPED)),
                (topics.plan, (PATH,)),
                (topics.goal, (POSE_STAMPED,)),
            ):
                conn = by_topic.get(name)
                if conn is not None:
                    _check_type(conn, types)
                    wanted.append(conn)
            pending_cmd: tuple[Any, int, bytes] | None = None  # the latest command, decoded when sampled
            frames: dict[str, str] = {}  # each topic's header.frame_id, as first seen
            for conn, t_ns, raw in reader.messages(connections=wanted):
                topic = conn.topic
                if topic == topics.odom:
                    if not observer.wants_odometry(t_ns):
                        continue
                    if pending_cmd is not None:
                        _command(observer, reader, *pending_cmd)
                        pending_cmd = None
                    msg = reader.deserialize(raw, conn.msgtype)
                    frames.setdefault(topic, msg.header.frame_id)
                    _odometry(observer, t_ns, msg)
                elif topic == topics.cmd:
                    pending_cmd = (conn, t_ns, raw)
                elif topic == topics.plan:
                    msg = reader.deserialize(raw, conn.msgtype)
                    frames.setdefault(topic, msg.header.frame_id)
                    observer.on_plan(t_ns, [(p.pose.position.x, p.pose.position.y) for p in msg.poses])
                else:
                    msg = reader.deserialize(raw, conn.msgtype)
                    frames.setdefault(topic, msg.header.frame_id)
                    observer.on_goal(t_ns, msg.pose.position.x, msg.pose.position.y)
    except ExportFormatError:
        raise
    except Exception as exc:  # rosbags' own errors, and what a damaged file makes its decoders raise
        raise ExportFormatError(f"damaged or unreadable ros2 bag {path}: {_reason(exc)}") from None
    observer.finish()
    odom_frame = frames.get(topics.odom)
    other = {t: f for t, f in frames.items() if t != topics.odom and f and odom_frame and f != odom_frame}
    for topic, frame in other.items():
        warn(
            f"{topic} is in frame '{frame}', odometry in '{odom_frame}': errors and cross-track figures take "
            "the two as one (true while the robot's odometry has not drifted from the map)"
        )
    if observer.foreign_stamps:
        warn(
            f"{observer.foreign_stamps} stamped commands carry another clock's stamp (over a minute off the "
            "recording's: use_sim_time?): no latency taken from them"
        )
    return Export(store.points(), store.runs(), store.runs_by_algorithm())


def _check_type(conn: Any, types: tuple[str, ...]) -> None:
    if conn.msgtype not in types:
        raise ExportFormatError(f"ros2 bag topic {conn.topic} is {conn.msgtype}, not {' or '.join(types)}")


def _odometry(observer: Observer, t_ns: int, msg: Any) -> None:
    p = msg.pose.pose
    q = p.orientation
    theta = quaternion_to_yaw({"x": q.x, "y": q.y, "z": q.z, "w": q.w})
    tw = msg.twist.twist
    observer.on_odometry(t_ns, p.position.x, p.position.y, theta, tw.linear.x, tw.angular.z)


def _command(observer: Observer, reader: Any, conn: Any, t_ns: int, raw: bytes) -> None:
    msg = reader.deserialize(raw, conn.msgtype)
    if conn.msgtype == TWIST_STAMPED:
        stamp = msg.header.stamp
        stamp_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
        observer.on_command(t_ns, msg.twist.linear.x, msg.twist.angular.z, stamp_ns if stamp_ns > 0 else None)
    else:
        observer.on_command(t_ns, msg.linear.x, msg.angular.z)


def _reason(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    return text if len(text) <= 200 else text[:197] + "…"
