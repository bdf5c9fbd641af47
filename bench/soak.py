#!/usr/bin/env python
"""Soak: the console's whole loop at 100 Hz against the bundled backend, watching memory and loss.

In this process: the TUI's own ``ControlLoop`` and ``Teleop`` (keys "pressed" every 0.3 s,
cycling through forward, curves and turns), the real ``RosLink`` (roslibpy) sending a stamped
command each 10 ms tick, analytics sampled into the store at 10 Hz while collecting, and the
tracker poller at 2 Hz, as the latency screen does. In the backend process: the rosbridge
endpoint, the tracker and the simulator. No Textual: the loop is what a long session keeps
running, the UI redraw is measured by ``bench/tui.py``.

Reported: resident memory (VmRSS) of each process after a warm-up and at the end, growth in
MB and extrapolated to MB per hour (least-squares slope over samples every 5 s), commands
sent, recorded by the tracker (``total_seen``) and unreported by the console's meter.

    python bench/soak.py --duration 3600       # the issue's hour
    python bench/soak.py --duration 60 --max-records 1000 --max-points 200 --check
                                               # CI: zero loss, growth <= 5 MB (exit 1 otherwise)

Last line: JSON.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import sys
import tempfile
import threading
import time

import httpx
from _common import emit, rss_kb, sleep_until

from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.control.loop import ControlLoop
from arbiter_tui.control.teleop import Teleop
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.embedded import EmbeddedBackend
from arbiter_tui.link.rosbridge import RosLink

KEYS = "iiuoijl"  # forward mostly, some curves and turns: the robot wanders and comes round
MAX_GROWTH_MB = 5.0


def rss_mb(pid: int) -> float:
    kb = rss_kb(pid)
    if kb is None:
        raise RuntimeError(f"process {pid} is gone")
    return kb / 1024.0


def slope_per_hour(samples: list[tuple[float, float]]) -> float:
    """Least-squares slope of (seconds, MB) samples, in MB per hour."""
    n = len(samples)
    if n < 2:
        return 0.0
    mt = sum(t for t, _ in samples) / n
    mm = sum(m for _, m in samples) / n
    var = sum((t - mt) ** 2 for t, _ in samples)
    if var == 0:
        return 0.0
    return sum((t - mt) * (m - mm) for t, m in samples) / var * 3600.0


def poll_forever(tracker: TrackerClient, stop: threading.Event, period: float = 0.5) -> None:
    async def loop() -> None:
        while not stop.is_set():
            started = time.monotonic()
            await tracker.poll()
            await asyncio.sleep(max(0.0, period - (time.monotonic() - started)))
        await tracker.aclose()

    asyncio.run(loop())


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=60.0, help="seconds of measured soak (default: 60)")
    p.add_argument("--rate", type=float, default=100.0, help="commands per second (default: 100)")
    p.add_argument(
        "--warmup",
        type=float,
        help="seconds before the first RSS reading (default: until the tracker's record window and the "
        "analytics ring buffer are full, plus 5 s: bounded buffers filling up is not a leak)",
    )
    p.add_argument("--max-records", type=int, default=10_000, help="the backend's record window (10000)")
    p.add_argument("--max-points", type=int, default=1000, help="the analytics ring buffer (1000)")
    p.add_argument(
        "--check", action="store_true", help=f"exit 1 on any loss or growth over {MAX_GROWTH_MB} MB"
    )
    args = p.parse_args()

    log = os.path.join(tempfile.gettempdir(), f"arbiter-soak-{os.getpid()}.log")
    backend = EmbeddedBackend.start(0, 0, log_file=log, extra_args=["--max-records", str(args.max_records)])
    api = f"http://127.0.0.1:{backend.api_port}"
    link = RosLink("127.0.0.1", backend.bridge_port)
    store = AnalyticsStore(max_data_points=args.max_points)
    teleop = Teleop(speed=0.5, turn=1.0, key_timeout=0.6)
    loop = ControlLoop(link, store, teleop)
    tracker = TrackerClient(api)
    stop = threading.Event()
    poller = threading.Thread(target=poll_forever, args=(tracker, stop), daemon=True)
    pids = {"console": os.getpid(), "backend": backend.proc.pid}
    try:
        deadline = time.monotonic() + 15
        while link.state != CONNECTED and time.monotonic() < deadline:
            time.sleep(0.05)
        if link.state != CONNECTED:
            raise SystemExit("soak: the link did not connect")
        time.sleep(0.3)  # subscriptions and the advertisement settle
        poller.start()
        store.start_collection()
        before = httpx.get(f"{api}/api/health", timeout=5).json()["total_seen"]
        sent0 = link.telemetry.meter.sent
        period = 1.0 / args.rate
        sample_every = max(1, round(args.rate / store.collection_rate))
        warmup = args.warmup
        if warmup is None:
            warmup = max(args.max_records / args.rate, args.max_points / store.collection_rate) + 5.0
        total = warmup + args.duration
        t0 = time.monotonic()
        start_rss: dict[str, float] = {}
        series: dict[str, list[tuple[float, float]]] = {k: [] for k in pids}
        next_rss = t0 + warmup
        tick = 0
        while True:
            now = time.monotonic()
            elapsed = now - t0
            if elapsed >= total:
                break
            if tick % round(0.3 * args.rate) == 0:
                teleop.press(KEYS[(tick // round(0.3 * args.rate)) % len(KEYS)], now)
            link.telemetry.meter.expire(now)
            loop.tick_control(now)
            if tick % sample_every == 0:
                loop.sample()
            if now >= next_rss:
                for name, pid in pids.items():
                    mb = rss_mb(pid)
                    start_rss.setdefault(name, mb)
                    series[name].append((elapsed - warmup, mb))
                next_rss += 5.0
                if len(series["backend"]) % 60 == 1:  # a progress line every 5 min, on stderr
                    rss = {n: round(v[-1][1], 2) for n, v in series.items()}
                    print(
                        f"soak: {elapsed - warmup:.0f} s, sent {link.telemetry.meter.sent - sent0}, "
                        f"rss MB {rss}",
                        file=sys.stderr,
                        flush=True,
                    )
            tick += 1
            sleep_until(t0 + tick * period)
        teleop.stop()
        loop.tick_control(time.monotonic())  # the final zero
        end_rss = {name: rss_mb(pid) for name, pid in pids.items()}
        time.sleep(2.5)  # every report back, or counted lost by the meter
        link.telemetry.meter.expire(time.monotonic())
        sent = link.telemetry.meter.sent - sent0
        recorded = httpx.get(f"{api}/api/health", timeout=5).json()["total_seen"] - before
        meter = link.telemetry.meter.summary()
    finally:
        stop.set()
        link.close()
        backend.stop()
    processes = {}
    for name in pids:
        growth = end_rss[name] - start_rss[name]
        processes[name] = {
            "rss_start_mb": round(start_rss[name], 2),
            "rss_end_mb": round(end_rss[name], 2),
            "growth_mb": round(growth, 2),
            "slope_mb_per_h": round(slope_per_hour(series[name]), 2),
        }
    lost = sent - recorded
    ok = lost == 0 and meter.lost == 0 and all(p["growth_mb"] <= MAX_GROWTH_MB for p in processes.values())
    emit(
        {
            "bench": "soak",
            "duration_s": args.duration,
            "warmup_s": round(warmup, 1),
            "max_records": args.max_records,
            "max_points": args.max_points,
            "rate_hz": args.rate,
            "sent": sent,
            "recorded": recorded,
            "lost": lost,
            "unreported": meter.lost,
            "rtt_p50_ms": meter.rtt_p50_ms,
            "store_points": len(store),
            "polls": tracker.view.polls,
            "poll_failures": tracker.view.failures,
            "processes": processes,
            "ok": ok,
        }
    )
    return 1 if args.check and not ok else 0


if __name__ == "__main__":
    sys.exit(main())
