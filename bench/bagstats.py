#!/usr/bin/env python
"""``arbiter-tui stats`` on a one-hour ros2 bag: time and peak memory, beside rosbags decoding the same
messages (issue 47: under 10 s, under 300 MB, at most 1.5x that floor).

Writes the bag first (rosbags, as ``ros2 bag record /odom /cmd_vel /plan /goal_pose`` would): odometry at
50 Hz and TwistStamped commands at 20 Hz throughout. With ``--long-run-min M`` the first M minutes are one
run along a plan of ``--plan-poses`` poses (5 cm apart, as Nav2's planners space them; the robot weaving
5 cm either side of it), started by the plan alone (NavigateToPose) and replanned every ``--replan-s`` from
where the robot is (Nav2's default: 1 s; 0: never); the rest of the hour (all of it without
``--long-run-min``) is a robot-side pure-pursuit controller driving the simulator to a new goal every 20 s
(each goal once, its plan once a second).

Then, each in a new process as a user runs it, ``--repeat`` times: ``arbiter-tui stats BAG --by run
--json`` (start-up included), and the **floor**: rosbags' ``AnyReader`` reading the same topics and
deserialising every message (no grading). Each run's peak RSS is the process's own (``wait4``). Prints
the medians; last line one JSON object.

    python bench/bagstats.py --minutes 60 --long-run-min 30 --plan-poses 14319
    python bench/bagstats.py --minutes 60 --storage sqlite3
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _common import emit
from rosbags.rosbag2 import StoragePlugin, Writer

from arbiter_core.simulator import DiffDriveSimulator
from tests.support.bags import T0_NS, TS, _header, _twist, drive, odometry_msg

ROOT = Path(__file__).resolve().parents[1]
SPACING_M = 0.05
TOPICS = ("/odom", "/cmd_vel", "/plan", "/goal_pose")
FLOOR = """
import sys
from pathlib import Path
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore
n = 0
with AnyReader([Path(sys.argv[1])], default_typestore=get_typestore(Stores.ROS2_KILTED)) as reader:
    conns = [c for c in reader.connections if c.topic in sys.argv[2].split(",")]
    for conn, _t, raw in reader.messages(connections=conns):
        reader.deserialize(raw, conn.msgtype)
        n += 1
print(n)
"""


def path_cdr(t_ns: int, xy: np.ndarray, frame: bytes = b"map") -> bytes:
    """A ``nav_msgs/msg/Path`` in little-endian CDR, as rosbags writes it (checked in ``main``), built
    with numpy: rosbags' serialiser takes ~65 ms for 7,000 poses, and the long run has 1,800 plans."""
    name = frame + b"\0"
    sec, nsec = divmod(t_ns, 1_000_000_000)

    def pad(buf: bytearray, n: int) -> None:
        buf.extend(b"\0" * (-(len(buf) - 4) % n))

    out = bytearray(b"\x00\x01\x00\x00")
    out += np.array([sec, nsec, len(name)], dtype="<u4").tobytes() + name
    pad(out, 4)
    out += np.array([len(xy)], dtype="<u4").tobytes()
    if not len(xy):
        return bytes(out)
    head = np.array([sec, nsec, len(name)], dtype="<u4").tobytes() + name
    pad(out, 4)
    out += head
    pad(out, 8)
    poses = np.zeros((len(xy), 7), dtype="<f8")
    poses[:, :2] = xy
    poses[:, 6] = 1.0  # orientation w
    out += poses[0].tobytes()
    rest = len(head) + (-len(head) % 8)  # every later pose starts 8-aligned: one layout for all
    rows = np.zeros((len(xy) - 1, rest + 56), dtype=np.uint8)
    rows[:, : len(head)] = np.frombuffer(head, dtype=np.uint8)
    rows[:, rest:] = poses[1:].view(np.uint8).reshape(-1, 56)
    return bytes(out) + rows.tobytes()


def long_path(poses: int) -> np.ndarray:
    """A winding path of ``poses`` poses 5 cm apart: long straights and turns of 1-3 m radius."""
    length = (poses - 1) * SPACING_M
    s = np.linspace(0.0, length, poses)
    curvature = 0.6 * np.sin(s / 7.0) * np.sin(s / 23.0)  # turns, and near-straight stretches between
    heading = np.concatenate(([0.0], np.cumsum((curvature[1:] + curvature[:-1]) / 2 * np.diff(s))))
    step = np.stack((np.cos(heading), np.sin(heading)), axis=1) * SPACING_M
    return np.concatenate(([[0.0, 0.0]], np.cumsum(step[1:], axis=0)), axis=0)


def write_long_run(writer: Writer, conns: dict, t0_ns: int, minutes: float, plan: np.ndarray,
                   replan_s: float) -> tuple[int, int]:  # fmt: skip
    """The long run; returns (messages, plan poses) written."""
    heading = np.unwrap(np.arctan2(*np.gradient(plan, axis=0)[:, ::-1].T))
    s_plan = np.arange(len(plan)) * SPACING_M
    duration = minutes * 60.0
    speed = s_plan[-1] / (duration - 10.0)  # arrives 10 s before the run's time is up, then stands
    count = poses = 0

    def put(topic: str, t: int, data: bytes) -> None:
        nonlocal count
        if topic not in conns:
            types = {"/plan": "nav_msgs/msg/Path", "/cmd_vel": "geometry_msgs/msg/TwistStamped",
                     "/odom": "nav_msgs/msg/Odometry"}  # fmt: skip
            conns[topic] = writer.add_connection(topic, types[topic], typestore=TS)
        writer.write(conns[topic], t, data)
        count += 1

    steps = round(duration * 50)
    replan_every = round(replan_s * 50) if replan_s > 0 else steps + 1
    for k in range(steps):
        t_ns = t0_ns + k * 20_000_000
        t = k / 50
        s = min(speed * t, s_plan[-1])
        moving = s < s_plan[-1]
        i = min(int(s / SPACING_M), len(plan) - 2)
        f = s / SPACING_M - i
        yaw = heading[i] + f * (heading[i + 1] - heading[i])
        weave = 0.05 * math.sin(2 * math.pi * t / 20.0) if moving else 0.0
        x = plan[i, 0] + f * (plan[i + 1, 0] - plan[i, 0]) - weave * math.sin(yaw)
        y = plan[i, 1] + f * (plan[i + 1, 1] - plan[i, 1]) + weave * math.cos(yaw)
        v = speed if moving else 0.0
        w = (heading[i + 1] - heading[i]) / SPACING_M * v
        if k % replan_every == 0 and moving:
            rest = plan[i:]
            put("/plan", t_ns + 1, path_cdr(t_ns, rest))
            poses += len(rest)
        if k % 5 in (0, 2):
            cmd = TS.types["geometry_msgs/msg/TwistStamped"](header=_header(t_ns - 3_000_000, "base_link"),
                                                             twist=_twist(v, w))  # fmt: skip
            put("/cmd_vel", t_ns + 2, TS.serialize_cdr(cmd, "geometry_msgs/msg/TwistStamped"))
        q = {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}
        odom = {"pose": {"pose": {"position": {"x": x, "y": y}, "orientation": q}},
                "twist": {"twist": {"linear": {"x": v}, "angular": {"z": w}}}}  # fmt: skip
        put("/odom", t_ns + 3, TS.serialize_cdr(odometry_msg(t_ns, odom), "nav_msgs/msg/Odometry"))
    return count, poses


def write_bag(path: Path, minutes: float, storage: str, long_min: float, plan_poses: int,
              replan_s: float) -> tuple[int, int]:  # fmt: skip
    """The bag; returns (messages, plan poses) written."""
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    count = poses = 0
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        conns: dict[str, object] = {}
        t0 = T0_NS
        if long_min > 0:
            count, poses = write_long_run(writer, conns, t0, long_min, long_path(plan_poses), replan_s)
            t0 += round(long_min * 60e9)
        sim = DiffDriveSimulator()
        for leg in range(max(0, round((minutes - long_min) * 3))):  # a goal every 20 s
            angle = leg * 2.4  # goals around the origin, 2 m out: each leg a different heading
            goal = (2.0 * math.cos(angle), 2.0 * math.sin(angle))
            rec = drive("pure_pursuit", goal=goal, seconds=20.0, t0_ns=t0 + leg * 20_000_000_000, sim=sim)
            for topic, t_ns, msg in rec.messages:
                if topic not in conns:
                    conns[topic] = writer.add_connection(topic, msg.__msgtype__, typestore=TS)
                conn = conns[topic]
                writer.write(conn, t_ns, TS.serialize_cdr(msg, conn.msgtype))  # type: ignore[attr-defined]
                count += 1
                poses += len(msg.poses) if topic == "/plan" else 0  # type: ignore[attr-defined]
    return count, poses


def _check_path_cdr() -> None:
    """The bench's own CDR writer against rosbags'."""
    t = TS.types
    check = long_path(5)
    q = t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
    poses = [
        t["geometry_msgs/msg/PoseStamped"](
            header=_header(7, "map"),
            pose=t["geometry_msgs/msg/Pose"](
                position=t["geometry_msgs/msg/Point"](x=x, y=y, z=0.0), orientation=q
            ),
        )
        for x, y in check
    ]
    msg = t["nav_msgs/msg/Path"](header=_header(7, "map"), poses=poses)
    assert path_cdr(7, check) == bytes(TS.serialize_cdr(msg, "nav_msgs/msg/Path")), (
        "path_cdr is not rosbags' CDR"
    )


def measured(cmd: list[str]) -> tuple[float, float, str]:
    """(seconds, peak RSS MB, stdout) of one process run to its end."""
    with tempfile.TemporaryFile() as out:
        t0 = time.perf_counter()
        env = {**os.environ, "PYTHONPATH": str(ROOT)}  # this checkout's arbiter_tui, not an installed one
        proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.PIPE, env=env, cwd=ROOT)
        _pid, status, usage = os.wait4(proc.pid, 0)
        elapsed = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        err = proc.stderr.read().decode() if proc.stderr else ""
        if proc.returncode:
            raise SystemExit(f"{' '.join(cmd[:4])}… failed ({proc.returncode}): {err.strip()}")
        out.seek(0)
        return elapsed, usage.ru_maxrss / 1024, out.read().decode()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--storage", choices=("mcap", "sqlite3"), default="mcap")
    parser.add_argument(
        "--long-run-min", type=float, default=0.0, help="minutes of one run along a long plan"
    )
    parser.add_argument("--plan-poses", type=int, default=14319)
    parser.add_argument("--replan-s", type=float, default=1.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--keep", type=Path, help="write the bag here and keep it (else a temporary dir)")
    args = parser.parse_args(argv)
    _check_path_cdr()
    with tempfile.TemporaryDirectory() as tmp:
        bag = args.keep or Path(tmp) / "hour"
        t0 = time.perf_counter()
        messages, poses = write_bag(bag, args.minutes, args.storage, args.long_run_min, args.plan_poses,
                                    args.replan_s)  # fmt: skip
        written_s = time.perf_counter() - t0
        size = sum(f.stat().st_size for f in bag.iterdir())
        stats_cmd = [sys.executable, "-m", "arbiter_tui.cli", "stats", str(bag), "--by", "run", "--json"]
        floor_cmd = [sys.executable, "-c", FLOOR, str(bag), ",".join(TOPICS)]
        runs: list[tuple[float, float]] = []
        floors: list[tuple[float, float]] = []
        body: dict = {}
        decoded = 0
        for _ in range(args.repeat):  # alternated, so both see the same machine
            s, rss, out = measured(stats_cmd)
            runs.append((s, rss))
            body = json.loads(out)
            s, rss, out = measured(floor_cmd)
            floors.append((s, rss))
            decoded = int(out)
    med = statistics.median(r[0] for r in runs)
    rss = max(r[1] for r in runs)
    floor = statistics.median(f[0] for f in floors)
    floor_rss = max(f[1] for f in floors)
    graded = [v for k, v in body.items() if k.startswith("run ")]
    longest = max(graded, key=lambda r: r["sampleCount"]) if graded else None
    print(
        f"{args.minutes:g} min bag ({args.storage}, {messages} messages, {poses} plan poses, "
        f"{size / 1e6:.1f} MB, written in {written_s:.1f} s): stats --by run in {med:.2f} s, peak RSS "
        f"{rss:.0f} MB (median of {args.repeat}; {len(graded)} runs); rosbags decoding the same "
        f"{decoded} messages: {floor:.2f} s, {floor_rss:.0f} MB; stats / floor = {med / floor:.2f}"
    )
    if longest is not None:
        t = longest["tracking"]
        print(
            f"longest run: {longest['sampleCount']} samples, {longest['outcome']}, xte mean "
            f"{t['xte_mean_m']} m, max {t['xte_max_m']} m, path ratio {t['path_ratio']}"
        )
    emit(
        {
            "bench": "bagstats",
            "minutes": args.minutes,
            "storage": args.storage,
            "long_run_min": args.long_run_min,
            "plan_poses": args.plan_poses if args.long_run_min else None,
            "replan_s": args.replan_s if args.long_run_min else None,
            "messages": messages,
            "plan_poses_written": poses,
            "bytes": size,
            "runs": len(graded),
            "stats_s": [round(r[0], 3) for r in runs],
            "stats_median_s": round(med, 3),
            "stats_peak_rss_mb": round(rss, 1),
            "floor_s": [round(f[0], 3) for f in floors],
            "floor_median_s": round(floor, 3),
            "floor_peak_rss_mb": round(floor_rss, 1),
            "stats_over_floor": round(med / floor, 3),
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
