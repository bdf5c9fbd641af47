#!/usr/bin/env python
"""``arbiter-tui stats`` on a one-hour ros2 bag: the issue's target is under 10 s.

Writes the bag first (rosbags, as ``ros2 bag record /odom /cmd_vel /plan /goal_pose`` would): a
robot-side pure-pursuit controller drives the simulator to a new goal every 20 s for ``--minutes``
(odometry 50 Hz, TwistStamped commands 20 Hz, the plan once a second, each goal once: ~255k messages an
hour), then times ``arbiter-tui stats BAG --by run --json`` as a user runs it (a new process: start-up
included), ``--repeat`` times, and prints the median. Last line: one JSON object.

    python bench/bagstats.py --minutes 60 --storage mcap
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import emit
from rosbags.rosbag2 import StoragePlugin, Writer

from arbiter_core.simulator import DiffDriveSimulator
from tests.support.bags import T0_NS, TS, drive


def write_hour(path: Path, minutes: float, storage: str) -> int:
    """The bag; returns its message count."""
    sim = DiffDriveSimulator()
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    count = 0
    legs = max(1, round(minutes * 3))  # a goal every 20 s
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        conns: dict[str, object] = {}
        for leg in range(legs):
            angle = leg * 2.4  # goals around the origin, 2 m out: each leg a different heading
            goal = (2.0 * math.cos(angle), 2.0 * math.sin(angle))
            rec = drive("pure_pursuit", goal=goal, seconds=20.0, t0_ns=T0_NS + leg * 20_000_000_000, sim=sim)
            for topic, t_ns, msg in rec.messages:
                if topic not in conns:
                    conns[topic] = writer.add_connection(topic, msg.__msgtype__, typestore=TS)
                conn = conns[topic]
                writer.write(conn, t_ns, TS.serialize_cdr(msg, conn.msgtype))  # type: ignore[attr-defined]
                count += 1
    return count


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--storage", choices=("mcap", "sqlite3"), default="mcap")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        bag = Path(tmp) / "hour"
        t0 = time.perf_counter()
        messages = write_hour(bag, args.minutes, args.storage)
        written_s = time.perf_counter() - t0
        size = sum(f.stat().st_size for f in bag.iterdir())
        times = []
        runs = 0
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            out = subprocess.run(
                [sys.executable, "-m", "arbiter_tui.cli", "stats", str(bag), "--by", "run", "--json"],
                capture_output=True,
                text=True,
                check=True,
            )
            times.append(time.perf_counter() - t0)
            runs = sum(1 for k in json.loads(out.stdout) if k.startswith("run "))
    median = statistics.median(times)
    print(
        f"{args.minutes:g} min bag ({args.storage}, {messages} messages, {size / 1e6:.1f} MB, written in "
        f"{written_s:.1f} s): stats --by run in {median:.2f} s (median of {args.repeat}; {runs} runs)"
    )
    emit(
        {
            "bench": "bagstats",
            "minutes": args.minutes,
            "storage": args.storage,
            "messages": messages,
            "bytes": size,
            "runs": runs,
            "stats_s": [round(t, 3) for t in times],
            "stats_median_s": round(median, 3),
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
