#!/usr/bin/env python
"""Service round trips across the bridge (``--transport ros``), both ways, one call at a time.

- ``ros->ws``: an rclpy client calls ``std_srvs/SetBool`` on a service a WebSocket client provides
  (``advertise_service``); the provider answers each ``call_service`` frame at once.
- ``ws->ros``: a WebSocket client's ``call_service`` to an rclpy ``SetBool`` server on the graph.

Starts its own backend on a random ROS domain. Last line: one JSON object.

    python bench/services.py --count 500
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import random
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

os.environ.setdefault("ROS_DOMAIN_ID", str(random.Random(os.getpid()).randint(101, 200)))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import aiohttp  # noqa: E402
import rclpy  # noqa: E402
from _common import emit, pct  # noqa: E402
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor  # noqa: E402
from std_srvs.srv import SetBool  # noqa: E402

from tests.support.backend import start_backend  # noqa: E402


async def ros_to_ws(node, port: int, count: int) -> list[float]:
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(f"ws://127.0.0.1:{port}/")
        await ws.send_json(
            {"op": "advertise_service", "service": "/bench/provided", "type": "std_srvs/SetBool"}
        )

        async def provide() -> None:
            async for msg in ws:
                frame = json.loads(msg.data)
                if frame.get("op") == "call_service":
                    await ws.send_json(
                        {
                            "op": "service_response",
                            "service": "/bench/provided",
                            "id": frame["id"],
                            "values": {"success": True},
                            "result": True,
                        }
                    )

        provider = asyncio.create_task(provide())
        client = node.create_client(SetBool, "/bench/provided")
        while not client.service_is_ready():
            await asyncio.sleep(0.01)
        times = []
        for _ in range(count):
            t0 = time.perf_counter()
            future = client.call_async(SetBool.Request(data=True))
            while not future.done():
                await asyncio.sleep(0)
            times.append((time.perf_counter() - t0) * 1e3)
        provider.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await provider
        return times


async def ws_to_ros(port: int, count: int) -> list[float]:
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(f"ws://127.0.0.1:{port}/")
        times = []
        i = 0
        while len(times) < count:
            i += 1
            t0 = time.perf_counter()
            await ws.send_json(
                {"op": "call_service", "id": i, "service": "/bench/on_graph", "args": {"data": True}}
            )
            reply = json.loads((await ws.receive(timeout=10)).data)
            if not reply.get("result"):  # the graph has not shown the server to the backend yet
                await asyncio.sleep(0.1)
                continue
            times.append((time.perf_counter() - t0) * 1e3)
        return times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=500)
    args = ap.parse_args()
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("bench_services", context=context)
    node.create_service(SetBool, "/bench/on_graph", lambda req, res: res)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)

    def spin() -> None:
        with contextlib.suppress(ExternalShutdownException):
            executor.spin()

    spinner = threading.Thread(target=spin, daemon=True)
    spinner.start()
    backend = start_backend("--transport", "ros", "--no-sim", timeout=30)
    try:
        a = asyncio.run(ros_to_ws(node, backend.bridge_port, args.count))
        b = asyncio.run(ws_to_ros(backend.bridge_port, args.count))
    finally:
        rc = backend.stop()
        if rc != 0:
            print(f"the backend exited {rc}: {backend.proc.stderr.read()[-2000:]}", file=sys.stderr)
        executor.shutdown(timeout_sec=2)
        spinner.join(2)
        node.destroy_node()
        context.try_shutdown()
    result = {"bench": "services", "count": args.count}
    for name, times in (("ros_to_ws", a), ("ws_to_ros", b)):
        times.sort()
        result.update({f"{name}_p50_ms": pct(times, 0.5), f"{name}_p95_ms": pct(times, 0.95)})
        print(f"{name}: p50 {pct(times, 0.5):.3f} ms, p95 {pct(times, 0.95):.3f} ms, max {times[-1]:.3f} ms")
    emit(result)


if __name__ == "__main__":
    main()
