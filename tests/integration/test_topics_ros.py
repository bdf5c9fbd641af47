"""``GET /api/topics`` in ROS mode against ground truth: real rclpy publishers of known rate, size and stamp.

The publishers record when they published; the truth for a window is computed from those times with
the same definitions (rate = (n - 1) / span; bandwidth = bytes / span * (n - 1) / n), so a loaded
machine that publishes late does not make the test wrong, only the publishers slower.
"""

import json
import time
from pathlib import Path

import httpx
import pytest

from ..support.backend import start_backend, wait_for
from ..support.ros import Odometry, Peer, domain, use_test_domain

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)

WINDOW = 3.0
OFFSET = 0.020  # the odometry's stamps are this far in the past


@pytest.fixture
def peer():
    p = Peer("arbiter_topics_peer")
    yield p
    p.close()


# The publishers run in a child process: stamping and publishing in this process would compete for the GIL
# with the test's own polling, which shows as delay. The child remembers when it published each message
# (CLOCK_MONOTONIC is one clock for every process of the machine) and the serialized size of each kind;
# "stop NAME" on stdin stops one, "dump" prints it all as JSON.
PUBLISHERS = r"""
import json, sys, threading, time, rclpy
from rclpy.serialization import serialize_message
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Image, LaserScan
from std_msgs.msg import String
OFFSET = float(sys.argv[1])
rclpy.init()
node = rclpy.create_node("arbiter_topics_truth")
scan = LaserScan(); scan.ranges = [1.0] * 360
image = Image(); image.height, image.width, image.step, image.encoding = 512, 683, 2049, "rgb8"
image.data = bytes(512 * 2049)  # ~1 MB
chatter = String(data="x" * 64)
def odom():
    msg = Odometry(); now = time.time() - OFFSET
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(now), int((now % 1) * 1e9)
    return msg
kinds = {"scan": (LaserScan, 10, lambda: scan), "odom": (Odometry, 50, odom),
         "chatter": (String, 200, lambda: chatter), "image": (Image, 15, lambda: image)}
times = {k: [] for k in kinds}
# DDS pads the payload to a multiple of 4 bytes: what a raw subscriber gets (and `ros2 topic bw` counts)
sizes = {k: (len(serialize_message(make())) + 3) // 4 * 4 for k, (_, _, make) in kinds.items()}
timers = {}
for name, (kind, hz, make) in kinds.items():
    pub = node.create_publisher(kind, "/arbiter_test/" + name, 10)
    def tick(pub=pub, make=make, name=name):
        pub.publish(make())
        times[name].append(time.monotonic())
    timers[name] = node.create_timer(1.0 / hz, tick)
threading.Thread(target=rclpy.spin, args=(node,), daemon=True).start()
print("ready", flush=True)
for line in sys.stdin:
    cmd, _, arg = line.strip().partition(" ")
    if cmd == "stop":
        timers[arg].cancel()
    elif cmd == "dump":
        print(json.dumps({"times": times, "sizes": sizes}), flush=True)
"""


def truth(times: list[float], size: int, start: float, end: float) -> tuple[float, float]:
    t = [x for x in times if start <= x <= end]
    span = t[-1] - t[0]
    return (len(t) - 1) / span, size * len(t) / span * (len(t) - 1) / len(t)


def topics(api: str) -> dict[str, dict]:
    return {t["name"]: t for t in httpx.get(f"{api}/api/topics", timeout=5).json()["topics"]}


@pytest.mark.timeout(120)
def test_rate_bandwidth_delay_and_silence_match_ground_truth():
    import os
    import subprocess
    import sys

    backend = start_backend(
        "--transport", "ros", "--no-sim", "--topics-window", str(WINDOW), "--topics", "/arbiter_test/*",
        timeout=30,
    )  # fmt: skip
    child = subprocess.Popen(
        [sys.executable, "-c", PUBLISHERS, str(OFFSET)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "ROS_DOMAIN_ID": str(domain())},
    )
    names = ("scan", "odom", "chatter", "image")
    try:
        assert child.stdout.readline().strip() == "ready"

        def all_full() -> bool:  # a whole window measured for each
            got = topics(backend.api)
            return all(
                (row := got.get(f"/arbiter_test/{n}")) and row["total"] > row["count"] > 0 for n in names
            )

        assert wait_for(all_full, 30), topics(backend.api)

        def measured_against_truth() -> tuple[dict, dict, list[tuple[str, float, float, float, float]]]:
            end = time.monotonic()
            got = topics(backend.api)
            child.stdin.write("dump\n")
            child.stdin.flush()
            sent = json.loads(child.stdout.readline())
            rows = []
            for name in names:
                row = got[f"/arbiter_test/{name}"]
                rate, bw = truth(sent["times"][name], sent["sizes"][name], end - WINDOW, end)
                rows.append((name, rate, row["rate_hz"], bw, row["bandwidth_bps"]))
            return got, sent, rows

        def within(rows: list[tuple[str, float, float, float, float]], rel: float) -> bool:
            return all(
                m == pytest.approx(r, rel=rel) and mb == pytest.approx(b, rel=rel) for _, r, m, b, mb in rows
            )

        # The truth is the publisher's send times; the monitor counts receive times. On a loaded machine
        # a burst of late deliveries moves a few messages across the window's edge (measured: odom 50.9
        # against 49.0 Hz under stress-ng on both cores), so a later window is asked for, not this one.
        last: list = []

        def matches_truth() -> bool:
            last[:] = measured_against_truth()
            return within(last[2], 0.02)

        assert wait_for(matches_truth, 2 * WINDOW, interval=WINDOW / 4), last[2]
        got, sent, rows = last
        for name in names:
            row = got[f"/arbiter_test/{name}"]
            assert row["mean_size_bytes"] == pytest.approx(sent["sizes"][name]), rows
            assert row["state"] == "ok" and row["publishers"] == 1
            assert row["publisher_nodes"] == ["/arbiter_topics_truth"]  # the monitor itself is not counted
        print("\ntopic      rate truth / measured (Hz)   bandwidth truth / measured (B/s)")  # pytest -s
        for name, rate, measured, bw, measured_bw in rows:
            print(f"{name:8} {rate:10.3f} / {measured:<10.3f} {bw:14.0f} / {measured_bw:.0f}")
        # the rate history, sampled once a second by the monitor's own thread (the same TopicWatch)
        history = got["/arbiter_test/scan"]["rate_history"]
        assert 1 <= len(history) <= 60 and history[-1] == pytest.approx(10.0, rel=0.1), history
        odom = got["/arbiter_test/odom"]
        print(f"odom delay: injected {OFFSET * 1e3:.1f} ms, measured mean {odom['delay_mean_ms']:.3f} ms")
        assert odom["stamped"] and got["/arbiter_test/scan"]["stamped"]
        chatter = got["/arbiter_test/chatter"]
        assert not chatter["stamped"] and chatter["delay_mean_ms"] is None

        # the delay is the offset plus the transport's own time, which the 1 MB frames sharing the
        # transport (head-of-line) and a loaded machine stretch: the camera stops, and the delay comes
        # within 1 ms in one of the next windows (a condition waited on, not one sample)
        child.stdin.write("stop image\n")
        child.stdin.flush()

        def delay_close() -> bool:
            return abs(topics(backend.api)["/arbiter_test/odom"]["delay_mean_ms"] - OFFSET * 1e3) <= 1.0

        assert wait_for(delay_close, 4 * WINDOW), topics(backend.api)["/arbiter_test/odom"]
        assert odom["malformed_stamps"] == 0

        # a publisher that stops: its row turns silent within two windows. It must have published
        # steadily (regular periods) for a whole window first (README "Stopped or just quiet?"). Behind
        # the camera and the 200 Hz chatter this child's own 10 Hz timer was measured irregular on a
        # loaded machine (period 0.138 s, spread 0.119 s): both stop, and the scan publishes two more
        # windows alone before it stops too
        child.stdin.write("stop chatter\n")
        child.stdin.flush()
        before = topics(backend.api)["/arbiter_test/scan"]["total"]
        assert wait_for(
            lambda: topics(backend.api)["/arbiter_test/scan"]["total"] >= before + 18 * WINDOW, 4 * WINDOW
        )
        # a stop is told from a pause only for a steady topic; a publisher starved by a loaded machine
        # (a gap of 5 periods) is steady again after STEADY_S of regular periods, so wait for it to be
        assert wait_for(lambda: topics(backend.api)["/arbiter_test/scan"]["steady"], 70)
        child.stdin.write("stop scan\n")
        child.stdin.flush()
        stop_at = time.monotonic()

        def scan_silent() -> bool:
            return topics(backend.api)["/arbiter_test/scan"]["state"] == "silent"

        assert wait_for(scan_silent, 2 * WINDOW + 5), topics(backend.api)["/arbiter_test/scan"]
        assert time.monotonic() - stop_at <= 2 * WINDOW + 1.0  # polled every 0.05 s; an API round trip
        assert topics(backend.api)["/arbiter_test/odom"]["state"] == "ok"
    finally:
        child.kill()
        child.wait()
        backend.stop()


def test_a_type_not_installed_is_listed_and_a_malformed_stamp_is_counted(peer, tmp_path: Path):
    """The backend cannot subscribe to a type it does not have (sensor_msgs hidden from it here): the topic
    is still listed, with its type, counts and the reason. A stamp whose nanoseconds are out of range is
    counted, not fatal."""
    from sensor_msgs.msg import Imu

    hidden = tmp_path / "hide"
    (hidden / "sensor_msgs").mkdir(parents=True)
    (hidden / "sensor_msgs" / "__init__.py").write_text("raise ImportError('hidden by the test')\n")
    import os

    env = {"PYTHONPATH": os.pathsep.join([str(hidden), os.environ.get("PYTHONPATH", "")])}
    backend = start_backend(
        "--transport", "ros", "--no-sim", "--topics-window", str(WINDOW), timeout=30, env=env
    )
    imu = peer.node.create_publisher(Imu, "/arbiter_test/imu", 10)
    odom = peer.node.create_publisher(Odometry, "/arbiter_test/bad_stamp", 10)
    bad = Odometry()
    bad.header.stamp.sec, bad.header.stamp.nanosec = 5, 2_000_000_000

    def listed_and_counted() -> bool:
        imu.publish(Imu())
        odom.publish(bad)
        got = topics(backend.api)
        return (
            "/arbiter_test/imu" in got
            and got.get("/arbiter_test/bad_stamp", {}).get("malformed_stamps", 0) >= 3
        )

    try:
        assert wait_for(listed_and_counted, 20), topics(backend.api)
        got = topics(backend.api)
        row = got["/arbiter_test/imu"]
        assert row["type"] == "sensor_msgs/msg/Imu"
        assert row["state"] == "unmeasured" and row["note"] == "type not installed here"
        assert row["publishers"] == 1 and row["rate_hz"] is None
        assert got["/arbiter_test/bad_stamp"]["delay_mean_ms"] is None
        assert got["/arbiter_test/bad_stamp"]["count"] >= 3  # the messages still count
        assert backend.proc.poll() is None
    finally:
        backend.stop()


def test_a_topic_the_relay_reads_is_measured_on_its_reader_not_a_second_one(peer):
    """A WebSocket client subscribes to a stamped topic the monitor measures: the monitor's own reader
    goes (two readers of a camera in one process stall DDS, docs/BENCHMARKS.md session 16) and the
    relay's messages are measured instead, each once (counted twice, the rate would double); when the
    client leaves, the monitor's reader comes back and the topic stays measured."""
    import roslibpy

    topic = "/arbiter_test/shared_odom"
    backend = start_backend(
        "--transport", "ros", "--no-sim", "--topics-window", str(WINDOW), "--topics", "/arbiter_test/*",
        timeout=30,
    )  # fmt: skip
    sent: list[float] = []
    pub = peer.node.create_publisher(Odometry, topic, 10)

    def tick() -> None:
        msg = Odometry()
        now = time.time() - OFFSET
        msg.header.stamp.sec, msg.header.stamp.nanosec = int(now), int((now % 1) * 1e9)
        pub.publish(msg)
        sent.append(time.monotonic())

    timer = peer.node.create_timer(1 / 25, tick)
    from rclpy.serialization import serialize_message

    size = (len(serialize_message(Odometry())) + 3) // 4 * 4

    def readers() -> set[str]:
        return {i.node_name for i in peer.node.get_subscriptions_info_by_topic(topic)}

    def row() -> dict:
        return topics(backend.api).get(topic, {})

    def rate_is_true() -> bool:
        end = time.monotonic()
        got = row()
        rate, _ = truth(list(sent), size, end - WINDOW, end)
        return got.get("rate_hz") is not None and got["rate_hz"] == pytest.approx(rate, rel=0.05)

    ros = roslibpy.Ros("127.0.0.1", backend.bridge_port)
    try:
        assert wait_for(lambda: "arbiter_topic_monitor" in readers(), 20), readers()
        assert wait_for(rate_is_true, 4 * WINDOW), row()

        ros.run(timeout=10)
        got: list = []
        sub = roslibpy.Topic(ros, topic, "nav_msgs/msg/Odometry")
        sub.subscribe(got.append)
        assert wait_for(lambda: readers() == {"arbiter_bridge"} and len(got) > 5, 20), readers()
        shared_from = row()["total"]
        assert wait_for(lambda: row()["total"] >= shared_from + 2 * WINDOW * 25, 4 * WINDOW)
        assert wait_for(rate_is_true, 4 * WINDOW), row()  # each message counted once
        measured = row()
        assert measured["mean_size_bytes"] == pytest.approx(size)
        assert measured["stamped"] and measured["delay_mean_ms"] >= OFFSET * 1e3 - 1.0
        assert measured["subscribers"] == 1  # the relay's reader: a client's, counted as before

        sub.unsubscribe()
        assert wait_for(lambda: "arbiter_topic_monitor" in readers(), 20), readers()
        back_from = row()["total"]
        assert wait_for(lambda: row()["total"] >= back_from + 25, 4 * WINDOW)
        assert wait_for(rate_is_true, 4 * WINDOW), row()
    finally:
        timer.cancel()
        ros.close()
        backend.stop()
