#!/usr/bin/env python
"""Cross-track error on a real robot's odometry, against plans whose true error is known, checked with an
independent rosbags + numpy computation (issue 47, item 1).

Takes a recording with ``nav_msgs/Odometry`` (any ros2 bag or lone ``.mcap``/``.db3``; e.g. evo's
``test/data/nav2_turtlebot.mcap``, a Nav2 TurtleBot run), and writes a copy with ``/plan`` messages as
Nav2 publishes them: every ``--replan-s`` the rest of the robot's own track from where it stands,
``--offset`` metres to its left, a pose every 5 cm. Two variants: the run started by the plan alone
(NavigateToPose, no ``/goal_pose``) and by a ``/goal_pose`` whose plan comes ``--plan-delay-s`` later.
``arbiter-tui stats --by run --json`` grades each (from ``--tree``: the checkout to measure, so main and
a branch can be compared), beside the figures computed here: the 10 Hz samples picked as the observer
picks them, each sample's distance to the plan in force (every sample against every segment), the run
ended where the robot stands within 0.15 m of the goal.

    python bench/reference_check.py /tmp/nav2_turtlebot.mcap --tree .
    python bench/reference_check.py /tmp/nav2_turtlebot.mcap --tree /path/to/main/checkout
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from _common import emit
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_KILTED)
T = TS.types
SAMPLE_NS = 100_000_000  # the console's 10 Hz collection
TOLERANCE_M = 0.15
STOPPED_V, STOPPED_W = 0.02, 0.05


def odometry(bag: Path) -> tuple[np.ndarray, list[tuple[int, bytes, object]]]:
    """(t ns, x, y, v, w, yaw) per message, and the raw messages to copy."""
    rows, raw = [], []
    with AnyReader([bag], default_typestore=TS) as reader:
        conns = [c for c in reader.connections if c.msgtype == "nav_msgs/msg/Odometry" and c.topic == "/odom"]
        for conn, t, data in reader.messages(connections=conns):
            m = reader.deserialize(data, conn.msgtype)
            p, q = m.pose.pose.position, m.pose.pose.orientation
            yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
            rows.append((t, p.x, p.y, m.twist.twist.linear.x, m.twist.twist.angular.z, yaw))
            raw.append((t, bytes(data), conn))
    return np.array(rows, dtype=np.float64), raw


def offset_track(xy: np.ndarray, offset: float, spacing: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """The track resampled every ``spacing`` metres along it and moved ``offset`` to its left; and, for
    each of the track's points, how far along it that point is (m)."""
    step = np.hypot(*np.diff(xy, axis=0).T)
    s = np.concatenate(([0.0], np.cumsum(step)))
    keep = np.concatenate(([True], step > 1e-9))
    grid = np.arange(0.0, s[-1], spacing)
    px, py = np.interp(grid, s[keep], xy[keep, 0]), np.interp(grid, s[keep], xy[keep, 1])
    heading = np.unwrap(np.arctan2(np.gradient(py), np.gradient(px)))
    return np.stack((px - offset * np.sin(heading), py + offset * np.cos(heading)), axis=1), s


def distances(x: np.ndarray, y: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Every sample against every segment (written here again, not taken from arbiter_tui)."""
    a, b = path[:-1], path[1:]
    d = b - a
    L2 = np.maximum((d**2).sum(axis=1), 1e-300)
    out = np.empty(len(x))
    for i, (px, py) in enumerate(zip(x, y, strict=True)):
        u = np.clip(((px - a[:, 0]) * d[:, 0] + (py - a[:, 1]) * d[:, 1]) / L2, 0.0, 1.0)
        out[i] = np.hypot(px - (a[:, 0] + u * d[:, 0]), py - (a[:, 1] + u * d[:, 1])).min()
    return out


def write(
    path: Path, raw: list, plans: list[tuple[int, np.ndarray]], goal: tuple[int, float, float] | None
) -> None:
    def header(t: int, frame: str) -> object:
        stamp = T["builtin_interfaces/msg/Time"](sec=t // 10**9, nanosec=t % 10**9)
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def pose(t: int, x: float, y: float) -> object:
        q = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
        p = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0), orientation=q)
        return T["geometry_msgs/msg/PoseStamped"](header=header(t, "odom"), pose=p)

    rows = [(t, "/odom", data) for t, data, _c in raw]
    for t, pts in plans:
        msg = T["nav_msgs/msg/Path"](header=header(t, "odom"), poses=[pose(t, x, y) for x, y in pts])
        rows.append((t, "/plan", bytes(TS.serialize_cdr(msg, "nav_msgs/msg/Path"))))
    if goal is not None:
        rows.append(
            (goal[0], "/goal_pose", bytes(TS.serialize_cdr(pose(*goal), "geometry_msgs/msg/PoseStamped")))
        )
    types = {
        "/odom": "nav_msgs/msg/Odometry",
        "/plan": "nav_msgs/msg/Path",
        "/goal_pose": "geometry_msgs/msg/PoseStamped",
    }
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {}
        for t, topic, data in sorted(rows, key=lambda r: r[0]):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, types[topic], typestore=TS)
            writer.write(conns[topic], t, data)


def expected(
    odom: np.ndarray, plans: list[tuple[int, np.ndarray]], first_plan: np.ndarray, goal: np.ndarray
) -> dict:
    """The observer's 10 Hz samples of the run (the first at the first odometry from the first
    reference's time, each next 100 ms on), ended at the first sample within 0.15 m of the goal and
    stopped; each sample's error against the reference in force, and against the first plan only; the
    path ratio against the first plan."""
    picked, due = [], plans[0][0]
    for i, t in enumerate(odom[:, 0]):
        if t < due:
            continue
        picked.append(i)
        due = t + SAMPLE_NS
        x, y, v, w = odom[i, 1:5]
        if math.hypot(x - goal[0], y - goal[1]) <= TOLERANCE_M and abs(v) < STOPPED_V and abs(w) < STOPPED_W:
            break
    s = odom[picked]
    times = np.array([t for t, _p in plans])
    in_force = np.searchsorted(times, s[:, 0], side="right") - 1
    e = np.empty(len(s))
    for k in np.unique(in_force):
        rows = in_force == k
        e[rows] = distances(s[rows, 1], s[rows, 2], plans[k][1])
    first = distances(s[:, 1], s[:, 2], first_plan)
    travelled = float(np.hypot(*np.diff(s[:, 1:3], axis=0).T).sum())
    ref = float(np.hypot(*np.diff(first_plan, axis=0).T).sum())
    # the seed's nine stats of the run (no command recorded: the measured velocity is the sample's)
    e_d = np.hypot(goal[0] - s[:, 1], goal[1] - s[:, 2])
    bearing = np.arctan2(goal[1] - s[:, 2], goal[0] - s[:, 1])
    e_th = np.abs((bearing - s[:, 5] + np.pi) % (2 * np.pi) - np.pi)
    v, w = np.abs(s[:, 3]), np.abs(s[:, 4])
    nine = {
        "sampleCount": len(s), "avgLinearVel": v.mean(), "avgAngularVel": w.mean(), "maxLinearVel": v.max(),
        "avgDistanceError": e_d.mean(), "avgHeadingError": e_th.mean(), "stdDevError": e_d.std(),
        "p95Error": np.sort(e_d)[int(0.95 * len(e_d))], "totalPathLength": travelled,
    }  # fmt: skip
    return {"samples": len(s), "xte_mean_m": float(e.mean()), "xte_max_m": float(e.max()),
            "first_plan_only_mean_m": float(first.mean()), "path_ratio": travelled / ref,
            "nine": {k: round(float(v), 6) for k, v in nine.items()}}  # fmt: skip


def graded(bag: Path, tree: Path) -> dict:
    out = subprocess.run(
        [sys.executable, "-m", "arbiter_tui.cli", "stats", str(bag), "--by", "run", "--json"],
        capture_output=True, text=True, cwd=tree, env={"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin"},
    )  # fmt: skip
    if out.returncode:
        return {"error": out.stderr.strip()}
    body = json.loads(out.stdout)
    runs = [v for k, v in body.items() if k.startswith("run ")]
    t = runs[0]["tracking"]
    figures = {k: t[k] for k in ("samples", "xte_mean_m", "xte_max_m", "path_ratio")}
    nine = ("sampleCount", "avgLinearVel", "avgAngularVel", "maxLinearVel", "avgDistanceError",
            "avgHeadingError", "stdDevError", "p95Error", "totalPathLength")  # fmt: skip
    return {
        "runs": len(runs),
        "outcome": runs[0]["outcome"],
        **figures,
        "nine": {k: runs[0][k] for k in nine},
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("bag", type=Path)
    p.add_argument("--tree", type=Path, default=Path(__file__).resolve().parents[1])
    p.add_argument("--offset", type=float, default=0.10)
    p.add_argument("--replan-s", type=float, default=1.0)
    p.add_argument("--plan-delay-s", type=float, default=0.5)
    args = p.parse_args(argv)
    odom, raw = odometry(args.bag)
    t0, t_end = int(odom[0, 0]), int(odom[-1, 0])
    step = round(args.replan_s * 1e9)
    track, along = offset_track(odom[:, 1:3], args.offset)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for variant in ("plan", "goal"):
            first = t0 + (round(args.plan_delay_s * 1e9) if variant == "goal" else 0)
            plans = []
            for t in range(first, t_end, step):  # the rest of the offset track, from where the robot is
                done = along[min(int(np.searchsorted(odom[:, 0], t)), len(along) - 1)]
                rest = track[int(done / 0.05) :]
                if len(rest) < 5:  # the robot is (nearly) there: the planner has nothing left to plan
                    break
                plans.append((t, rest))
            goal_xy = plans[0][1][-1]
            goal = (t0, float(goal_xy[0]), float(goal_xy[1])) if variant == "goal" else None
            bag = Path(tmp) / variant
            write(bag, raw, plans, goal)
            first_plan = plans[0][1]
            if variant == "goal":  # before its plan, the straight line from where the robot stood
                plans = [(t0, np.array([odom[0, 1:3], goal_xy])), *plans]
            figures = expected(odom, plans, first_plan, goal_xy)
            results[variant] = {"stats": graded(bag, args.tree), "numpy": figures}
    for variant, r in results.items():
        print(f"{variant}: stats {r['stats']}")
        print(f"{'':>{len(variant)}}  numpy {r['numpy']}")
    emit({"bench": "reference_check", "bag": args.bag.name, "tree": str(args.tree), **results})
    return 0


if __name__ == "__main__":
    sys.exit(main())
