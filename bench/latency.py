#!/usr/bin/env python
"""One-way latency and round trip of stamped commands: the TUI's own sending code -> bridge -> tracker.

Starts the backend (as the TUI's embedded mode does) on free ports, connects the
TUI's ``RosLink`` (roslibpy) and sends ``--count`` commands at ``--rate`` Hz. The
one-way figure is the tracker's (receive wall time minus the envelope stamp,
same host so same clock); the round trip is the link's own measurement (send
until the ``/latency_report`` for that seq arrives). The floor is a raw TCP
loopback one-way time (TCP_NODELAY, another process) measured in the same run
with the same count and rate. Last line: one JSON object.

    python bench/latency.py --count 2000 --rate 100
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import random
import socket
import sys
import time

from _common import emit, pct, sleep_until

from arbiter_core import envelope, stats
from arbiter_core.urls import rosbridge_endpoint, tracker_beside, tracker_endpoint
from arbiter_tui.latency.clocksync import LatencyMeter
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.embedded import EmbeddedBackend
from arbiter_tui.link.rosbridge import RosLink


def _tcp_receiver(port_q, result_q, count: int) -> None:
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(1)
    port_q.put(srv.getsockname()[1])
    conn, _ = srv.accept()
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    f = conn.makefile("rb")
    out = []
    for _ in range(count):
        line = f.readline()
        now = time.time_ns()
        if not line:
            break
        out.append((now - int(line)) / 1e6)
    result_q.put(out)


def tcp_floor(count: int, rate: float) -> list[float]:
    ctx = mp.get_context("spawn")
    port_q, result_q = ctx.Queue(), ctx.Queue()
    proc = ctx.Process(target=_tcp_receiver, args=(port_q, result_q, count), daemon=True)
    proc.start()
    s = socket.create_connection(("127.0.0.1", port_q.get(timeout=20)))
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    t = time.monotonic()
    for _ in range(count):
        sleep_until(t)
        s.sendall(b"%d\n" % time.time_ns())
        t += 1.0 / rate
    res = result_q.get(timeout=60)
    s.close()
    proc.join(5)
    return res


def _dds_receiver(result_q, count: int) -> None:
    """The DDS floor's subscriber: its own process, rclpy, std_msgs/String, the product's QoS."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import String

    from arbiter_backend.ros.bus import default_qos

    rclpy.init()
    node = rclpy.create_node("arbiter_floor_sub")
    out: list[float] = []
    node.create_subscription(
        String, "/arbiter_floor", lambda m: out.append((time.time_ns() - int(m.data)) / 1e6), default_qos()
    )
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    deadline = time.monotonic() + 60 + count / 50
    while len(out) < count and time.monotonic() < deadline:
        ex.spin_once(timeout_sec=0.1)
    result_q.put(out)
    node.destroy_node()
    rclpy.try_shutdown()


def dds_floor(count: int, rate: float) -> list[float]:
    """rclpy publisher -> subscriber across two processes with the product's QoS and message type:
    the floor under the ``--transport ros`` path, measured in the same run."""
    import rclpy
    from std_msgs.msg import String

    from arbiter_backend.ros.bus import default_qos

    ctx = mp.get_context("spawn")
    result_q = ctx.Queue()
    proc = ctx.Process(target=_dds_receiver, args=(result_q, count), daemon=True)
    proc.start()
    rclpy.init()
    node = rclpy.create_node("arbiter_floor_pub")
    pub = node.create_publisher(String, "/arbiter_floor", default_qos())
    deadline = time.monotonic() + 20
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)
    t = time.monotonic()
    for _ in range(count):
        sleep_until(t)
        pub.publish(String(data=str(time.time_ns())))
        t += 1.0 / rate
    res = result_q.get(timeout=60)
    node.destroy_node()
    rclpy.try_shutdown()
    proc.join(5)
    return res


def plain_client(url: str, api: str, count: int, rate: float) -> list[float]:
    """A plain roslibpy client as any user script writes it (Twisted transport, Nagle left on): it
    subscribes to /cmd_vel_measured and publishes at ``rate`` with every 7th envelope malformed (the
    tracker rejects those). One-way latencies of the good ones, from the tracker's records."""
    import httpx
    import roslibpy

    ros = roslibpy.Ros(url, port=None)
    ros.run(timeout=10)
    try:
        roslibpy.Topic(ros, "/cmd_vel_measured", "geometry_msgs/Twist").subscribe(lambda _m: None)
        pub = roslibpy.Topic(ros, "/stamped_cmd_vel", "std_msgs/String")
        pub.advertise()
        time.sleep(0.5)
        since = httpx.get(f"{api}/api/latency?limit=0").json()["last_rx_seq"]
        t = time.monotonic()
        for i in range(count):
            sleep_until(t)
            data = "{bad" if i % 7 == 6 else envelope.build(0.1, 0.0, seq=i)
            pub.publish(roslibpy.Message({"data": data}))
            t += 1.0 / rate
        time.sleep(1.0)
        out: list[float] = []
        while True:
            body = httpx.get(f"{api}/api/latency", params={"since": since, "limit": 1000}).json()
            out += [r["latency_ms"] for r in body["records"]]
            since = body["records"][-1]["rx_seq"] if body["records"] else since
            if not body.get("more"):
                return out
    finally:
        ros.close()


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--count", type=int, default=2000)
    p.add_argument("--rate", type=float, default=100.0)
    p.add_argument("--warmup", type=int, default=50)
    p.add_argument("--transport", choices=("embedded", "ros"), default="embedded")
    p.add_argument(
        "--plain-client", action="store_true",
        help="also: a plain roslibpy client (Nagle on, subscribed, some envelopes rejected) at 200 Hz",
    )  # fmt: skip
    p.add_argument("--rosbridge", help="measure a server that already runs (ours elsewhere, or the stock "
                   "rosbridge_server with our tracker behind it) instead of starting one")  # fmt: skip
    p.add_argument("--tracker", help="with --rosbridge: its tracker's API (default: the same host, 8085)")
    a = p.parse_args()
    if a.transport == "ros" or a.rosbridge:
        # DDS on this host only, on a domain of its own: other runs on the machine are not measured
        os.environ.setdefault("ROS_DOMAIN_ID", str(random.Random(os.getpid()).randint(101, 200)))
        os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

    if a.rosbridge:
        bridge = rosbridge_endpoint(a.rosbridge)
        api = (tracker_endpoint(a.tracker) if a.tracker else tracker_beside(bridge)).url.rstrip("/")
        backend = None
        link = RosLink(bridge.host, bridge.port, path=bridge.path, secure=bridge.secure)
    else:
        backend = EmbeddedBackend.start(0, 0, transport=a.transport, timeout=30)
        api = f"http://127.0.0.1:{backend.api_port}"
        link = RosLink("127.0.0.1", backend.bridge_port)
    try:
        deadline = time.monotonic() + 15
        while link.state != CONNECTED and time.monotonic() < deadline:
            time.sleep(0.05)
        if link.state != CONNECTED:
            print("latency: the link did not connect", file=sys.stderr)
            return 1
        time.sleep(1.0 if a.transport == "ros" else 0.3)
        for _ in range(a.warmup):
            link.send(0.1, 0.0)
            time.sleep(1.0 / a.rate)
        time.sleep(0.5)
        meter = link.telemetry.meter = LatencyMeter(history=a.count, offset_window_s=3600.0)
        t = time.monotonic()
        for _ in range(a.count):
            sleep_until(t)
            link.send(0.1, 0.0)
            t += 1.0 / a.rate
        deadline = time.monotonic() + 5
        while meter.matched < a.count and time.monotonic() < deadline:
            time.sleep(0.02)
        meter.expire(time.monotonic() + meter.lost_after_s + 1)
        samples = meter.samples()
        plain = plain_client(link.url, api, a.count, 200.0) if a.plain_client else []
    finally:
        link.close()
        if backend is not None:
            backend.stop()

    one_way = [s.raw_ms for s in samples]
    rtt = [s.rtt_ms for s in samples]
    floor = tcp_floor(min(a.count, 2000), a.rate)
    dds = dds_floor(min(a.count, 2000), a.rate) if a.transport == "ros" else []
    est = meter.offset()
    p50, floor50 = pct(one_way, 0.5), pct(floor, 0.5)
    emit(
        {
            "bench": "latency",
            "transport": a.transport,
            "server": a.rosbridge or "ours, started by the bench",
            "count": a.count,
            "rate_hz": a.rate,
            "one_way_p50_ms": p50,
            "one_way_p95_ms": pct(one_way, 0.95),
            "one_way_p99_ms": pct(one_way, 0.99),
            "one_way_mean_ms": round(stats.mean(one_way), 4) if one_way else None,
            "one_way_max_ms": round(stats.maximum(one_way), 4) if one_way else None,
            "corrected_p50_ms": pct([s.corrected_ms for s in samples], 0.5),
            "rtt_p50_ms": pct(rtt, 0.5),
            "rtt_p95_ms": pct(rtt, 0.95),
            "rtt_p99_ms": pct(rtt, 0.99),
            "offset_ms": None if est is None else round(est.offset_ms, 4),
            "offset_uncertainty_ms": None if est is None else round(est.uncertainty_ms, 4),
            "negative": meter.negative,
            "lost": meter.lost,
            "floor_p50_ms": floor50,
            "floor_p95_ms": pct(floor, 0.95),
            "p50_over_floor": round(p50 / floor50, 1) if p50 and floor50 else None,
            **(
                {
                    "dds_floor_p50_ms": pct(dds, 0.5),
                    "dds_floor_p95_ms": pct(dds, 0.95),
                    "dds_floor_p99_ms": pct(dds, 0.99),
                    "p50_over_dds_floor": round(p50 / pct(dds, 0.5), 2) if p50 else None,
                    "rtt_p50_over_dds_floor": round(pct(rtt, 0.5) / pct(dds, 0.5), 2) if rtt else None,
                }
                if dds
                else {}
            ),
            **(
                {
                    "plain_client_n": len(plain),
                    "plain_client_p50_ms": pct(plain, 0.5),
                    "plain_client_p95_ms": pct(plain, 0.95),
                    "plain_client_p99_ms": pct(plain, 0.99),
                    "plain_client_max_ms": round(max(plain), 4),
                }
                if plain
                else {}
            ),
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
