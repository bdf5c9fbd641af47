#!/usr/bin/env python
"""``GET /api/latency`` response time with 10,000 records kept, while 50 pollers poll at 2 Hz.

Fills the tracker with ``--records`` commands over the WebSocket endpoint, then
runs ``--pollers`` async httpx clients, each polling at ``--rate`` Hz (the
seed's dashboard rate) for ``--duration`` seconds, and times every request
(default ``limit``, as the TUI and the seed's page ask). Last line: JSON.

    python bench/api.py --duration 30
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import time

import aiohttp
import httpx
from _common import emit, pct
from throughput import frame

from arbiter_tui.link.embedded import EmbeddedBackend


async def fill(bridge: int, n: int) -> None:
    async with aiohttp.ClientSession() as s, s.ws_connect(f"ws://127.0.0.1:{bridge}") as ws:
        adv = {"op": "advertise", "topic": "/stamped_cmd_vel", "type": "std_msgs/String"}
        await ws.send_str(json.dumps(adv))
        for i in range(n):
            await ws.send_str(frame(i))


async def poller(
    api: str, rate: float, phase: float, until: float, out: list[float], errors: list[int]
) -> None:
    # aiohttp rather than httpx for the 50 pollers: in one Python process on a small machine httpx's
    # own per-request cost dominated the figure; we want the server's.
    async with aiohttp.ClientSession() as http:
        nxt = time.monotonic() + phase / rate  # independent dashboards are not in lockstep
        while nxt < until:
            await asyncio.sleep(max(0.0, nxt - time.monotonic()))
            t = time.perf_counter()
            async with http.get(f"{api}/api/latency") as r:
                await r.read()
                status = r.status
            out.append((time.perf_counter() - t) * 1000.0)
            if status != 200:
                errors.append(status)
            nxt += 1.0 / rate


async def run(bridge: int, api: str, a: argparse.Namespace) -> dict:
    await fill(bridge, a.records)
    async with httpx.AsyncClient() as http:
        while (await http.get(f"{api}/api/health")).json()["records_count"] < min(a.records, 10_000):
            await asyncio.sleep(0.1)
    times: list[float] = []
    errors: list[int] = []
    until = time.monotonic() + a.duration
    await asyncio.gather(
        *(poller(api, a.rate, i / a.pollers, until, times, errors) for i in range(a.pollers))
    )
    return {
        "requests": len(times),
        "errors": len(errors),
        "p50_ms": pct(times, 0.5),
        "p95_ms": pct(times, 0.95),
        "p99_ms": pct(times, 0.99),
        "max_ms": round(max(times), 3),
    }


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--records", type=int, default=10_000)
    p.add_argument("--pollers", type=int, default=50)
    p.add_argument("--rate", type=float, default=2.0)
    p.add_argument("--duration", type=float, default=30.0)
    a = p.parse_args()
    backend = EmbeddedBackend.start(0, 0, timeout=30)
    try:
        res = asyncio.run(run(backend.bridge_port, f"http://127.0.0.1:{backend.api_port}", a))
    finally:
        backend.stop()
    emit({"bench": "api", "records": a.records, "pollers": a.pollers, "rate_hz": a.rate,
          "duration_s": a.duration, **res})  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
