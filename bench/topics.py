"""What watching every topic costs the backend, beside deserialising them as ``ros2 topic hz`` does.

One publisher process sends a 10 Hz LaserScan, a 50 Hz stamped Odometry, a 200 Hz String and a ~1 MB
15 Hz Image on a ROS domain of its own. In the same run, alternating, ``--repeat`` times, each for
``--seconds``:

- ``not watching``: ``arbiter-backend --transport ros --no-sim --topics-exclude '*'`` (relay, tracker,
  monitor node, nothing measured);
- ``watching``: the same backend measuring the four topics (raw subscriptions, stamps from the bytes);
- ``deserialising``: an rclpy process subscribing to the four topics with ordinary (deserialising)
  callbacks that note the receive time and size of each message, as ``ros2 topic hz``/``bw`` do;
- ``idle rclpy``: the same process with no subscription (its floor).

CPU is the process's user + system time (/proc) over the phase. Prints per-phase medians and
``watch_cost = watching - not watching`` against ``deserialise_cost = deserialising - idle rclpy``.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _common import emit  # noqa: E402

from tests.support.backend import start_backend  # noqa: E402

TOPICS = ("/bench/scan", "/bench/odom", "/bench/chatter", "/bench/image")

PUBLISHER = r"""
import time, rclpy
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Image, LaserScan
from std_msgs.msg import String
rclpy.init()
n = rclpy.create_node("bench_topics_publisher")
scan = LaserScan(); scan.ranges = [1.0] * 360
image = Image(); image.height, image.width, image.step, image.encoding = 512, 683, 2049, "rgb8"
image.data = bytes(512 * 2049)
chatter = String(data="x" * 64)
import sys
kinds = sys.argv[1].split(",")
pubs = {k: n.create_publisher(t, "/bench/" + k, 10)
        for k, t in (("scan", LaserScan), ("odom", Odometry), ("chatter", String), ("image", Image))
        if k in kinds}
def odom():
    m = Odometry(); t = time.time() - 0.02
    m.header.stamp.sec, m.header.stamp.nanosec = int(t), int((t % 1) * 1e9)
    pubs["odom"].publish(m)
if "scan" in pubs: n.create_timer(0.1, lambda: pubs["scan"].publish(scan))
if "odom" in pubs: n.create_timer(0.02, odom)
if "chatter" in pubs: n.create_timer(0.005, lambda: pubs["chatter"].publish(chatter))
if "image" in pubs: n.create_timer(1 / 15, lambda: pubs["image"].publish(image))
print("ready", flush=True)
rclpy.spin(n)
"""

SUBSCRIBER = r"""
import sys, time, rclpy
from rclpy.qos import QoSProfile
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Image, LaserScan
from std_msgs.msg import String
rclpy.init()
n = rclpy.create_node("bench_topics_deserialiser")
seen = {}
def note(topic):
    def cb(msg):
        seen.setdefault(topic, []).append((time.monotonic(), msg))
        if len(seen[topic]) > 1000:
            del seen[topic][:500]
    return cb
if sys.argv[1] == "subscribe":
    for k, t in (("scan", LaserScan), ("odom", Odometry), ("chatter", String), ("image", Image)):
        if k in sys.argv[2].split(","):
            n.create_subscription(t, "/bench/" + k, note(k), QoSProfile(depth=100))
print("ready", flush=True)
rclpy.spin(n)
"""


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure(pid: int, seconds: float) -> float:
    """The process's CPU over ``seconds``, as a % of one core."""
    c0, t0 = cpu_seconds(pid), time.monotonic()
    time.sleep(seconds)
    return 100 * (cpu_seconds(pid) - c0) / (time.monotonic() - t0)


def spawn(code: str, *args: str, env: dict[str, str]) -> subprocess.Popen[str]:
    proc = subprocess.Popen([sys.executable, "-c", code, *args], stdout=subprocess.PIPE, text=True, env=env)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "ready"
    return proc


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0, help="length of each phase (default 10)")
    ap.add_argument("--repeat", type=int, default=3, help="rounds of the four phases (default 3)")
    ap.add_argument("--warmup", type=float, default=3.0, help="seconds before each phase is measured")
    ap.add_argument(
        "--kinds", default="scan,odom,chatter,image", help="which of the four publishers run (default: all)"
    )
    args = ap.parse_args()
    env = {**os.environ, "ROS_DOMAIN_ID": str(random.Random(os.getpid()).randint(101, 200)),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONUNBUFFERED": "1"}  # fmt: skip
    os.environ.update(env)
    publisher = spawn(PUBLISHER, args.kinds, env=env)
    phases: dict[str, list[float]] = {
        "not watching": [],
        "watching": [],
        "deserialising": [],
        "idle rclpy": [],
    }
    try:
        for _ in range(args.repeat):
            for name in phases:
                if name in ("not watching", "watching"):
                    extra = ("--topics-exclude", "*") if name == "not watching" else ("--topics", "/bench/*")
                    backend = start_backend("--transport", "ros", "--no-sim", *extra, timeout=30, env=env)
                    pid, stop = backend.proc.pid, backend.stop
                else:
                    what = "subscribe" if name == "deserialising" else "idle"
                    proc = spawn(SUBSCRIBER, what, args.kinds, env=env)
                    pid, stop = proc.pid, proc.kill
                try:
                    time.sleep(args.warmup)
                    phases[name].append(measure(pid, args.seconds))
                    if name == "watching":  # what it measured, so the run shows the topics were seen
                        import httpx

                        got = httpx.get(f"{backend.api}/api/topics", timeout=5).json()["topics"]
                        rates = {t["name"]: round(t["rate_hz"] or 0, 2) for t in got if t["name"] in TOPICS}
                        print(json.dumps({"watched_rates_hz": rates}), flush=True)
                finally:
                    stop()
                print(json.dumps({"phase": name, "cpu_pct": round(phases[name][-1], 2)}), flush=True)
    finally:
        publisher.kill()
    med = {k: statistics.median(v) for k, v in phases.items()}
    watch_cost = med["watching"] - med["not watching"]
    deser_cost = med["deserialising"] - med["idle rclpy"]
    emit(
        {
            "bench": "topics",
            "seconds": args.seconds,
            "repeat": args.repeat,
            "kinds": args.kinds,
            **{f"{k.replace(' ', '_')}_cpu_pct": round(v, 2) for k, v in med.items()},
            "watching_over_not_watching": round(med["watching"] / med["not watching"], 2),
            "watch_cost_pct": round(watch_cost, 2),
            "deserialise_cost_pct": round(deser_cost, 2),
            "watch_cost_over_deserialise_cost": round(watch_cost / deser_cost, 3) if deser_cost > 0 else None,
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
