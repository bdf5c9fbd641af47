#!/usr/bin/env python
"""The highest stamped-command rate the bridge + tracker sustain with zero loss, for 1 and 10 clients.

For each client count it runs trials of ``--duration`` seconds at a fixed total
rate (clients share it evenly; WebSocket clients over loopback, frames sent in
1 ms batches), doubling the rate until a trial loses a command (the tracker's
``total_seen`` falls short of what was sent, or anything is rejected), then
bisects between the last clean and the first lossy rate. Last line: JSON.

    python bench/throughput.py --duration 10          # the issue's 10 s trials
    python bench/throughput.py --duration 2 --start 4000
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import time

import aiohttp
import httpx
from _common import emit

from arbiter_tui.link.embedded import EmbeddedBackend


def frame(seq: int) -> str:
    stamp = time.time_ns() // 1000 / 1000.0
    twist = '"twist":{"linear":{"x":0.1},"angular":{"z":0.0}}'
    data = f'{{"header":{{"stamp":{stamp!r},"seq":{seq}}},{twist}}}'
    return json.dumps({"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": data}})


API_TIMEOUT_S = 30.0  # an overloaded backend (ROS mode past its rate) answers late, not never


async def trial(bridge: int, api: str, clients: int, rate: float, duration: float) -> dict:
    async with httpx.AsyncClient(timeout=API_TIMEOUT_S) as http:
        before = (await http.get(f"{api}/api/health")).json()
        async with aiohttp.ClientSession() as session:
            sockets = [await session.ws_connect(f"ws://127.0.0.1:{bridge}") for _ in range(clients)]
            for ws in sockets:
                await ws.send_str(
                    json.dumps({"op": "advertise", "topic": "/stamped_cmd_vel", "type": "std_msgs/String"})
                )
            await asyncio.sleep(0.2)
            sent = 0
            t0 = time.monotonic()
            while True:
                elapsed = time.monotonic() - t0
                if elapsed >= duration:
                    break
                due = int(elapsed * rate) - sent
                for _ in range(max(0, due)):
                    await sockets[sent % clients].send_str(frame(sent))
                    sent += 1
                await asyncio.sleep(0.001)
            achieved = sent / (time.monotonic() - t0)
            # a backlog still draining is not loss: wait until the count stops moving for 1 s
            seen, last_change, deadline = -1, time.monotonic(), time.monotonic() + 60
            while time.monotonic() < deadline:
                try:
                    h = (await http.get(f"{api}/api/health")).json()
                except httpx.TimeoutException:  # the API cannot answer while the backlog drains
                    await asyncio.sleep(0.1)
                    continue
                now_seen = h["total_seen"] - before["total_seen"]
                if now_seen != seen:
                    seen, last_change = now_seen, time.monotonic()
                if seen >= sent or time.monotonic() - last_change > 1.0:
                    break
                await asyncio.sleep(0.1)
            for ws in sockets:
                await ws.close()
    rejected = h["rejected"] - before["rejected"]
    return {"rate": rate, "sent": sent, "seen": seen, "lost": sent - seen, "rejected": rejected,
            "achieved": round(achieved)}  # fmt: skip


def is_clean(r: dict) -> bool:
    """Zero loss, nothing rejected, and the sender actually reached the rate asked for."""
    return r["lost"] == 0 and r["rejected"] == 0 and r["achieved"] >= 0.97 * r["rate"]


async def search(bridge: int, api: str, clients: int, start: float, duration: float, limit: float) -> dict:
    good, bad, trials = 0.0, None, []
    rate = start
    while rate <= limit:
        r = await trial(bridge, api, clients, rate, duration)
        trials.append(r)
        clean = is_clean(r)
        print(json.dumps({"clients": clients, **r, "clean": clean}), flush=True)
        if not clean:
            bad = rate
            break
        good = rate
        rate *= 2
    if bad is not None:
        for _ in range(3):
            mid = (good + bad) / 2
            r = await trial(bridge, api, clients, mid, duration)
            trials.append(r)
            clean = is_clean(r)
            print(json.dumps({"clients": clients, **r, "clean": clean}), flush=True)
            good, bad = (mid, bad) if clean else (good, mid)
    return {"max_zero_loss_rate": round(good), "first_lossy_rate": None if bad is None else round(bad)}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=10.0)
    p.add_argument("--start", type=float, default=5000.0)
    p.add_argument("--limit", type=float, default=200_000.0)
    p.add_argument("--transport", choices=("embedded", "ros"), default="embedded")
    a = p.parse_args()
    backend = EmbeddedBackend.start(0, 0, transport=a.transport, timeout=30)
    api = f"http://127.0.0.1:{backend.api_port}"
    try:
        one = asyncio.run(search(backend.bridge_port, api, 1, a.start, a.duration, a.limit))
        ten = asyncio.run(search(backend.bridge_port, api, 10, a.start, a.duration, a.limit))
    finally:
        backend.stop()
    emit({"bench": "throughput", "transport": a.transport, "duration_s": a.duration,
          "one_client": one, "ten_clients": ten})  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
