"""The bundled backend in one asyncio process: bus, tracker, simulator, rosbridge endpoint, HTTP API.

aiohttp serves both the WebSocket endpoint and the HTTP API: one event loop,
one dependency, and a command goes from the socket reader to the tracker with
no thread hop and no spin-loop wait (the stock rosbridge_server waits up to
10 ms per frame in its spin loop).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import time
from dataclasses import dataclass, field
from typing import Any

from aiohttp import web

from . import api, bridge
from .bus import TopicBus
from .core.kinematics import DEFAULT_LIMITS, Limits
from .simulator import RATE_HZ, DiffDriveSimulator
from .tracker import LatencyTracker

log = logging.getLogger(__name__)

TOPIC_STAMPED = "/stamped_cmd_vel"
TOPIC_MEASURED = "/cmd_vel_measured"
TOPIC_REPORT = "/latency_report"
TOPIC_ODOM = "/odom"
TYPE_STRING = "std_msgs/msg/String"
TYPE_TWIST = "geometry_msgs/msg/Twist"
TYPE_ODOM = "nav_msgs/msg/Odometry"


@dataclass
class BackendConfig:
    host: str = "127.0.0.1"
    bridge_port: int = 9090
    api_port: int = 8085
    deploy_mode: str = "native"
    sim: bool = True
    bridge: bool = True
    max_records: int = 10_000
    cmd_timeout: float = 0.5
    limits: Limits = field(default_factory=lambda: DEFAULT_LIMITS)


def twist_msg(v: float, w: float) -> dict[str, Any]:
    return {"linear": {"x": v, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": w}}


class Backend:
    def __init__(self, config: BackendConfig) -> None:
        self.config = config
        self.bus = TopicBus()
        self.tracker = LatencyTracker(
            deploy_mode=config.deploy_mode,
            max_records=config.max_records,
            cmd_timeout=config.cmd_timeout,
            limits=config.limits,
        )
        self.simulator = (
            DiffDriveSimulator(config.limits, cmd_timeout=config.cmd_timeout) if config.sim else None
        )
        self.endpoint = bridge.RosbridgeEndpoint(self.bus)
        self._runners: list[web.AppRunner] = []
        self._tasks: list[asyncio.Task[None]] = []
        self.bridge_port: int | None = None
        self.api_port: int | None = None
        for topic, type_name in (
            (TOPIC_STAMPED, TYPE_STRING),
            (TOPIC_MEASURED, TYPE_TWIST),
            (TOPIC_REPORT, TYPE_STRING),
            (TOPIC_ODOM, TYPE_ODOM),
        ):
            self.bus.declare(topic, type_name)
        self.bus.subscribe(TOPIC_STAMPED, self._on_stamped)
        if self.simulator is not None:
            sim = self.simulator
            self.bus.subscribe(TOPIC_MEASURED, lambda m: sim.on_twist(m, time.monotonic()))

    def _on_stamped(self, msg: dict[str, Any]) -> None:
        recv_ns = time.time_ns()
        accepted = self.tracker.on_stamped(msg.get("data"), recv_ns)
        if accepted is None:
            return
        self.bus.publish(TOPIC_REPORT, {"data": json.dumps(accepted.record, allow_nan=False)})
        self.bus.publish(TOPIC_MEASURED, twist_msg(accepted.linear_x, accepted.angular_z))

    async def _watchdog(self) -> None:
        period = min(0.05, self.config.cmd_timeout / 4)
        while True:
            await asyncio.sleep(period)
            if self.tracker.watchdog_due():
                log.info("no command for %.2fs: publishing zero twist", self.config.cmd_timeout)
                self.bus.publish(TOPIC_MEASURED, twist_msg(0.0, 0.0))

    async def _sim_loop(self) -> None:
        assert self.simulator is not None
        period = 1.0 / RATE_HZ
        loop = asyncio.get_running_loop()
        next_t = loop.time()
        while True:
            odom = self.simulator.tick(time.monotonic(), time.time_ns())
            self.bus.publish(TOPIC_ODOM, odom)
            next_t += period
            delay = next_t - loop.time()
            if delay < -period:  # fell behind (suspended?): resynchronise instead of bursting
                next_t = loop.time()
                delay = 0.0
            await asyncio.sleep(max(0.0, delay))

    async def _serve(self, app: web.Application, port: int) -> int:
        runner = web.AppRunner(app, access_log=None, handle_signals=False)
        await runner.setup()
        self._runners.append(runner)
        site = web.TCPSite(runner, self.config.host, port, reuse_address=True)
        await site.start()
        server = site._server
        assert server is not None and server.sockets  # type: ignore[union-attr]
        return int(server.sockets[0].getsockname()[1])  # type: ignore[union-attr]

    async def start(self) -> None:
        try:
            if self.config.bridge:
                self.bridge_port = await self._serve(bridge.make_app(self.endpoint), self.config.bridge_port)
            self.api_port = await self._serve(api.make_app(self.tracker), self.config.api_port)
        except BaseException:
            await self.stop()
            raise
        loop = asyncio.get_running_loop()
        self._tasks.append(loop.create_task(self._watchdog()))
        if self.simulator is not None:
            self._tasks.append(loop.create_task(self._sim_loop()))

    async def stop(self) -> None:
        for task in self._tasks:
            task.cancel()
        for task in self._tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self._tasks.clear()
        await self.endpoint.close_all()
        for runner in self._runners:
            await runner.cleanup()
        self._runners.clear()

    def describe(self) -> str:
        parts = []
        if self.bridge_port is not None:
            parts.append(f"rosbridge=ws://{self.config.host}:{self.bridge_port}")
        parts.append(f"api=http://{self.config.host}:{self.api_port}")
        parts.append(f"deploy_mode={self.config.deploy_mode}")
        parts.append(f"sim={'on' if self.simulator else 'off'}")
        return "arbiter-backend listening: " + " ".join(parts)
