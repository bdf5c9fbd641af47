"""ros2 bags as a robot records them, written with rosbags: a controller on the robot drives the
simulator to a goal (50 Hz odometry, commands at 20 Hz, the plan replanned every second, the goal once)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from arbiter_core.controllers import make_controller
from arbiter_core.kinematics import quaternion_to_yaw
from arbiter_core.mission import Mission
from arbiter_core.simulator import DiffDriveSimulator

TS = get_typestore(Stores.ROS2_KILTED)
T0_NS = 1_800_000_000_000_000_000


@dataclass
class Recording:
    """The messages of one drive, each (topic, log time ns, message), and the robot's true poses."""

    messages: list[tuple[str, int, object]] = field(default_factory=list)
    poses: list[tuple[int, float, float]] = field(default_factory=list)  # (t ns, x, y) at 50 Hz


def _time(t_ns: int) -> object:
    return TS.types["builtin_interfaces/msg/Time"](sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000)


def _header(t_ns: int, frame: str = "odom") -> object:
    return TS.types["std_msgs/msg/Header"](stamp=_time(t_ns), frame_id=frame)


def _pose_msg(x: float, y: float, yaw: float = 0.0) -> object:
    t = TS.types
    q = t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))
    return t["geometry_msgs/msg/Pose"](position=t["geometry_msgs/msg/Point"](x=x, y=y, z=0.0), orientation=q)


def _twist(v: float, w: float) -> object:
    t = TS.types
    v3 = t["geometry_msgs/msg/Vector3"]
    return t["geometry_msgs/msg/Twist"](linear=v3(x=v, y=0.0, z=0.0), angular=v3(x=0.0, y=0.0, z=w))


def odometry_msg(t_ns: int, odom: dict) -> object:
    t = TS.types
    p = odom["pose"]["pose"]
    tw = odom["twist"]["twist"]
    cov = np.zeros(36)
    return t["nav_msgs/msg/Odometry"](
        header=_header(t_ns),
        child_frame_id="base_link",
        pose=t["geometry_msgs/msg/PoseWithCovariance"](
            pose=_pose_msg(p["position"]["x"], p["position"]["y"], quaternion_to_yaw(p["orientation"])),
            covariance=cov,
        ),
        twist=t["geometry_msgs/msg/TwistWithCovariance"](
            twist=_twist(tw["linear"]["x"], tw["angular"]["z"]), covariance=cov
        ),
    )


def path_msg(t_ns: int, points: list[tuple[float, float]]) -> object:
    t = TS.types
    poses = [
        t["geometry_msgs/msg/PoseStamped"](header=_header(t_ns, "map"), pose=_pose_msg(x, y))
        for x, y in points
    ]
    return t["nav_msgs/msg/Path"](header=_header(t_ns, "map"), poses=poses)


def drive(
    algorithm: str = "pure_pursuit",
    goal: tuple[float, float] = (2.0, 1.0),
    stamped: bool = True,
    cmd_delay_ms: float = 3.0,
    seconds: float = 20.0,
    t0_ns: int = T0_NS,
    sim: DiffDriveSimulator | None = None,
) -> Recording:
    """A robot-side controller driving to ``goal`` from where ``sim`` stands, recorded as a bag would:
    a goal_pose, a plan (start to goal, 20 points) republished every second, TwistStamped (or Twist)
    commands at 20 Hz stamped ``cmd_delay_ms`` before the recorder got them, odometry at 50 Hz."""
    sim = sim or DiffDriveSimulator()
    rec = Recording()
    controller = make_controller(algorithm)
    start = (sim.state.pose.x, sim.state.pose.y)
    mission = Mission.route([goal], start=start)
    plan = [
        (start[0] + (goal[0] - start[0]) * k / 19, start[1] + (goal[1] - start[1]) * k / 19)
        for k in range(20)
    ]
    goal_msg = TS.types["geometry_msgs/msg/PoseStamped"](header=_header(t0_ns, "map"), pose=_pose_msg(*goal))
    rec.messages.append(("/goal_pose", t0_ns, goal_msg))
    steps = round(seconds * 50)
    for n in range(steps):
        t_ns = t0_ns + n * 20_000_000
        now = t_ns / 1e9
        if n % 50 == 0:
            rec.messages.append(("/plan", t_ns + 1, path_msg(t_ns, plan)))
        if n % 5 in (0, 2):  # 20 Hz: 40 and 60 ms apart in turn, as a 20 Hz timer beside a 50 Hz one
            pose = sim.state.pose
            mission = mission.advanced(pose)
            v, w = (0.0, 0.0) if mission.done else controller.command(pose, mission)
            sim.on_twist({"linear": {"x": v}, "angular": {"z": w}}, now)
            stamp = t_ns - round(cmd_delay_ms * 1e6)
            msg = (
                TS.types["geometry_msgs/msg/TwistStamped"](
                    header=_header(stamp, "base_link"), twist=_twist(v, w)
                )
                if stamped
                else _twist(v, w)
            )
            rec.messages.append(("/cmd_vel", t_ns + 2, msg))
        odom = sim.tick(now, t_ns)
        rec.messages.append(("/odom", t_ns + 3, odometry_msg(t_ns, odom)))
        rec.poses.append((t_ns, sim.state.pose.x, sim.state.pose.y))
    rec.messages.sort(key=lambda m: m[1])
    return rec


def write_bag(
    path: Path,
    rec: Recording,
    storage: str = "mcap",
    extra: dict[str, str] | None = None,
    compression: str | None = None,
    raw: list[tuple[str, str, str, int, bytes]] | None = None,
    empty: dict[str, str] | None = None,
) -> Path:
    """``rec`` as a rosbag2 directory at ``path`` (``mcap`` or ``sqlite3`` storage; ``compression``:
    ``file`` or ``message``, zstd). ``raw``: connections written as they are, (topic, type, its
    definition text, log time, bytes), e.g. a type no parser here reads; ``empty``: topics (and their
    types) recorded with no message."""
    from rosbags.rosbag2 import CompressionFormat, CompressionMode

    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    types = {
        "/odom": "nav_msgs/msg/Odometry",
        "/plan": "nav_msgs/msg/Path",
        "/goal_pose": "geometry_msgs/msg/PoseStamped",
        **(extra or {}),
    }
    writer = Writer(path, version=9, storage_plugin=plugin)
    if compression is not None:
        writer.set_compression(CompressionMode[compression.upper()], CompressionFormat.ZSTD)
    with writer:
        conns = {
            topic: writer.add_connection(topic, msgtype, typestore=TS)
            for topic, msgtype in (empty or {}).items()
        }
        for topic, msgtype, msgdef, _t, _data in raw or ():
            if topic not in conns:
                conns[topic] = writer.add_connection(
                    topic, msgtype, msgdef=msgdef, rihs01="RIHS01_" + "0" * 64
                )
        rows = [(t_ns, topic, msg, None) for topic, t_ns, msg in rec.messages]
        rows += [(t_ns, topic, None, data) for topic, _m, _d, t_ns, data in raw or ()]
        for t_ns, topic, msg, data in sorted(rows, key=lambda r: r[0]):
            if topic not in conns:
                msgtype = types.get(topic) or msg.__msgtype__
                conns[topic] = writer.add_connection(topic, msgtype, typestore=TS)
            writer.write(
                conns[topic], t_ns, data if data is not None else TS.serialize_cdr(msg, conns[topic].msgtype)
            )
    return path


def scan_msg(t_ns: int, ranges: list[float], range_min: float = 0.12, range_max: float = 3.5) -> object:
    """A 360-beam sensor_msgs/LaserScan in the robot's frame."""
    return TS.types["sensor_msgs/msg/LaserScan"](
        header=_header(t_ns, "base_scan"), angle_min=0.0, angle_max=2 * math.pi,
        angle_increment=2 * math.pi / 360, time_increment=0.0, scan_time=0.2, range_min=range_min,
        range_max=range_max,
        ranges=np.asarray(ranges, dtype=np.float32), intensities=np.zeros(len(ranges), dtype=np.float32),
    )  # fmt: skip


def status_msg(t_ns: int, *goals: tuple[int, int]) -> object:
    """An action_msgs/GoalStatusArray: (goal number, status) each (status 2 executing, 4 succeeded,
    5 canceled, 6 aborted)."""
    t = TS.types
    return t["action_msgs/msg/GoalStatusArray"](
        status_list=[
            t["action_msgs/msg/GoalStatus"](
                goal_info=t["action_msgs/msg/GoalInfo"](
                    goal_id=t["unique_identifier_msgs/msg/UUID"](uuid=np.full(16, n, dtype=np.uint8)),
                    stamp=_time(t_ns),
                ),
                status=status,
            )
            for n, status in goals
        ]
    )
