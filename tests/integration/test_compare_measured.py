"""`arbiter-tui compare --latency measured` against a real tracker: the sweep starts from its records."""

import asyncio
import json
import subprocess
import sys

import aiohttp
import httpx
import pytest

from arbiter_core import envelope
from arbiter_core.stats import percentile

from ..support.backend import start_backend, wait_for


def test_the_sweep_takes_the_trackers_p50_and_p95():
    backend = start_backend("--no-sim")
    try:

        async def send(n: int) -> None:
            async with (
                aiohttp.ClientSession() as s,
                s.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}") as ws,
            ):
                await ws.send_json(
                    {"op": "advertise", "topic": "/stamped_cmd_vel", "type": "std_msgs/String"}
                )
                for seq in range(n):
                    data = envelope.build(0.0, 0.0, seq=seq)
                    await ws.send_json({"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": data}})

        asyncio.run(send(40))
        api = backend.api
        assert wait_for(lambda: httpx.get(f"{api}/api/latency", timeout=5).json()["stats"]["count"] == 40, 10)
        records = httpx.get(f"{api}/api/latency", params={"limit": 1000}, timeout=5).json()["records"]
        latencies = [r["latency_ms"] for r in records]
        out = subprocess.run(
            [sys.executable, "-m", "arbiter_tui.cli", "compare", "--latency", "measured",
             "--measured-from", api, "--mission", "square", "--json"],
            capture_output=True, text=True, timeout=60,
        )  # fmt: skip
        assert out.returncode == 0, out.stderr
        links = [cell["link"]["latency_ms"] for cell in json.loads(out.stdout)["sweep"]]
        assert links == pytest.approx([max(0.0, percentile(latencies, q)) for q in (0.5, 0.95)])
    finally:
        backend.stop()
