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
import socket
import sys
import time

from _common import emit, pct, sleep_until

from arbiter_core import envelope, stats
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


def plain_client(bridge_port: int, api: str, count: int, rate: float) -> list[float]:
    """A plain roslibpy client as any user script writes it (Twisted transport, Nagle left on): it
    subscribes to /cmd_vel_measured and publishes at ``rate`` with every 7th envelope malformed (the
    tracker rejects those). One-way latencies of the good ones, from the tracker's records."""
    import httpx
    import roslibpy

    ros = roslibpy.Ros("127.0.0.1", bridge_port)
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
    a = p.parse_args()

    backend = EmbeddedBackend.start(0, 0, transport=a.transport, timeout=30)
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
        meter = link.telemetry.meter = LatencyMeter(history=a.count, offset_window=a.count)
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
        plain = (
            plain_client(backend.bridge_port, f"http://127.0.0.1:{backend.api_port}", a.count, 200.0)
            if a.plain_client
            else []
        )
    finally:
        link.close()
        backend.stop()

    one_way = [s.raw_ms for s in samples]
    rtt = [s.rtt_ms for s in samples]
    floor = tcp_floor(min(a.count, 2000), a.rate)
    est = meter.offset()
    p50, floor50 = pct(one_way, 0.5), pct(floor, 0.5)
    emit(
        {
            "bench": "latency",
            "transport": a.transport,
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
