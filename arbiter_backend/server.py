"""The embedded transport: the bundled backend in one asyncio process: bus, tracker, simulator, rosbridge
endpoint, HTTP API (its configuration, shared with the ROS transport: ``config.py``, ``servers.py``).

aiohttp serves both the WebSocket endpoint and the HTTP API: one event loop,
one dependency, and a command goes from the socket reader to the tracker with
no thread hop and no spin-loop wait (the stock rosbridge_server waits up to
10 ms per frame in its spin loop).
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
import time
from typing import Any

from arbiter_core import envelope, topics
from arbiter_core.simulator import RATE_HZ

from . import autonomy as autonomy_mod
from .autonomy import AutonomyService
from .bus import TopicBus
from .config import BackendConfig
from .servers import Servers
from .topicwatch import EmbeddedTopics, follow

log = logging.getLogger(__name__)
TOPICS_TICK_S = 0.25  # the topic monitor's beat (its rate history samples once a second of it)


class Backend(Servers):
    """The embedded transport: an in-process topic bus instead of DDS."""

    def __init__(self, config: BackendConfig) -> None:
        super().__init__(config)
        self.bus = TopicBus()
        self.tracker = config.make_tracker()
        self.simulator = config.make_simulator() if config.sim else None
        self.sim_enabled = self.simulator is not None
        self.endpoint = config.make_endpoint(self.bus)
        self._tasks: list[asyncio.Task[None]] = []
        # relative names under the namespace, as the ROS transport's nodes resolve them
        ns = config.namespace
        self.topic_stamped = topics.resolve(topics.STAMPED, ns)
        self.topic_measured = topics.resolve(topics.MEASURED, ns)
        self.topic_report = topics.resolve(topics.REPORT, ns)
        self.topic_odom = topics.resolve(topics.ODOM, ns)
        for topic, type_name in (
            (self.topic_stamped, topics.TYPE_STRING),
            (self.topic_measured, topics.MEASURED_TYPES[config.measured_type]),
            (self.topic_report, topics.TYPE_STRING),
            (self.topic_odom, topics.TYPE_ODOM),
        ):
            self.bus.declare(topic, type_name)
        self.bus.subscribe(self.topic_stamped, self._on_stamped)
        # the backend's own publishers, so that the topic monitor counts them
        self.bus.advertise(self.topic_measured, topics.MEASURED_TYPES[config.measured_type])
        self.bus.advertise(self.topic_report, topics.TYPE_STRING)
        self.topics = EmbeddedTopics(self.bus, config.make_topic_watch())
        if self.simulator is not None:
            self.bus.advertise(self.topic_odom, topics.TYPE_ODOM)
            sim = self.simulator
            self.bus.subscribe(self.topic_measured, lambda m: sim.on_twist(m, time.monotonic()))
        self.autonomy: AutonomyService | None = None
        if config.autonomy:
            self.autonomy = self._make_autonomy(ns)

    def _make_autonomy(self, ns: str) -> AutonomyService:
        """The robot-side controller: on the odometry, its commands onto the tracker's own path."""
        where = {key: topics.resolve(key, ns) for key in (autonomy_mod.PLAN, autonomy_mod.GOAL)}
        self.bus.advertise(where[autonomy_mod.PLAN], autonomy_mod.TYPE_PATH, latch=True)
        self.bus.advertise(where[autonomy_mod.GOAL], autonomy_mod.TYPE_POSE_STAMPED, latch=True)
        self.bus.advertise(self.topic_stamped, topics.TYPE_STRING)
        seq = itertools.count(1)

        def send(v: float, w: float) -> None:
            self.bus.publish(self.topic_stamped, {"data": envelope.build(v, w, seq=next(seq))})

        service = AutonomyService(
            lambda key, msg: self.bus.publish(where[key], msg), send, lambda: topics.stamp(time.time_ns())
        )
        self.bus.subscribe(self.topic_odom, service.on_odometry)
        return service

    def _on_stamped(self, msg: dict[str, Any]) -> None:
        recv_ns = time.time_ns()
        accepted = self.tracker.on_stamped(msg.get("data"), recv_ns)
        if accepted is None:
            return
        self.bus.publish(self.topic_report, {"data": accepted.text})
        if accepted.forward is not None:
            v, w = accepted.forward
            twist = topics.measured_message(v, w, self.config.measured_type, recv_ns)
            self.bus.publish(self.topic_measured, twist)

    def publish_zero(self) -> None:
        """One zero twist on the robot's command output now, as the deadman sends (a fleet console's
        stop: arbiter_backend/fleet.py)."""
        zero = topics.measured_message(0.0, 0.0, self.config.measured_type, time.time_ns())
        self.bus.publish(self.topic_measured, zero)

    async def _watchdog(self) -> None:
        period = min(0.05, self.config.cmd_timeout / 4)
        while True:
            await asyncio.sleep(period)
            self.supervisor.beat("watchdog")
            if self.tracker.watchdog_due():
                log.info("no command for %.2fs: publishing zero twist", self.config.cmd_timeout)
                self.bus.publish(
                    self.topic_measured,
                    topics.measured_message(0.0, 0.0, self.config.measured_type, time.time_ns()),
                )

    async def _topics_loop(self) -> None:
        """The topic monitor's own beat: new topics watched, each one's rate sampled once a second."""
        while True:
            await asyncio.sleep(TOPICS_TICK_S)
            self.topics.tick()
            self.supervisor.beat("topic-monitor")

    async def _sim_loop(self) -> None:
        assert self.simulator is not None
        period = 1.0 / RATE_HZ
        loop = asyncio.get_running_loop()
        next_t = loop.time()
        while True:
            self.supervisor.beat("simulator")
            odom = self.simulator.tick(time.monotonic(), time.time_ns())
            self.bus.publish(self.topic_odom, odom)
            next_t += period
            delay = next_t - loop.time()
            if delay < -period:  # fell behind (suspended?): resynchronise instead of bursting
                next_t = loop.time()
                delay = 0.0
            await asyncio.sleep(max(0.0, delay))

    async def start(self) -> None:
        await self.start_servers(
            self.endpoint if self.config.bridge else None, self.tracker, self.topics, self.autonomy
        )
        sup = self.supervisor
        follow(sup, "topic-monitor", self.topics.watch, "monitor")
        self._tasks.append(sup.task("watchdog", self._watchdog, give_up=False))  # the robot's stop
        self._tasks.append(sup.task("topic-monitor", self._topics_loop))
        if self.simulator is not None:
            self._tasks.append(sup.task("simulator", self._sim_loop))

    async def stop(self) -> None:
        for task in self._tasks:
            task.cancel()
        for task in self._tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self._tasks.clear()
        await self.stop_servers(self.endpoint)
