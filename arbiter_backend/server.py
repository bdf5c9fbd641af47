"""The bundled backend in one asyncio process: bus, tracker, simulator, rosbridge endpoint, HTTP API.

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
import ssl
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from aiohttp import web

from arbiter_core import auth, envelope, topics
from arbiter_core.hostclock import HostClock
from arbiter_core.kinematics import DEFAULT_LIMITS, Limits
from arbiter_core.listening import format_listening
from arbiter_core.simulator import RATE_HZ, DiffDriveSimulator
from arbiter_core.topicstats import WINDOW_S

from . import api, bridge, rosapi
from . import autonomy as autonomy_mod
from .autonomy import AutonomyService
from .bridge import MAX_FRAME_BYTES, WS_PING_S, RosbridgeEndpoint
from .bridge.exposure import Exposure
from .bus import Bus, TopicBus
from .pacing import WAIT_S as PACED_WAIT_S
from .supervise import Supervisor
from .topicwatch import EmbeddedTopics, TopicFilter, TopicWatch, follow
from .tracker import DEFAULT_MAX_COMMAND_AGE_MS, LatencyTracker

log = logging.getLogger(__name__)
TOPICS_TICK_S = 0.25  # the topic monitor's beat (its rate history samples once a second of it)


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
    max_command_age_ms: float = DEFAULT_MAX_COMMAND_AGE_MS  # 0: off
    limits: Limits = field(default_factory=lambda: DEFAULT_LIMITS)
    measured_type: str = "twist"  # a key of topics.MEASURED_TYPES
    transport: str = "embedded"  # or "ros"
    token: str | None = None  # required from every client when set (see auth.py)
    allow_remote: bool = False  # without it only loopback addresses may be bound
    namespace: str = ""  # every topic of the backend under it (arbiter_core.topics.namespace form)
    tls_cert: Path | None = None  # with tls_key: serve wss:// and https:// (PEM files)
    tls_key: Path | None = None
    topics_include: str | None = None  # comma-separated globs of the topics /api/topics watches (None: all)
    topics_exclude: str | None = None
    topics_window: float = WINDOW_S
    ws_ping: float = WS_PING_S  # the endpoint's liveness pings (seconds; 0: none)
    paced_wait: float = PACED_WAIT_S  # a slow client's big frame holds a small one this long (s; 0: any)
    max_frame: int = MAX_FRAME_BYTES  # a client's frames above this are answered with a status error
    topics_glob: str | None = None  # comma-separated globs of the topics clients may reach (None: all)
    services_glob: str | None = None  # ... and of the services they may call
    actions_glob: str | None = None  # ... and of the actions they may send goals to or provide
    params_glob: str | None = None  # ... and of the parameters rosapi reads and sets (names, no node)
    autonomy: bool = False  # the robot-side controller, driven through /api/autonomy (embedded transport)

    def make_endpoint(
        self, bus: Bus, namespace: str | None = None, node: str = topics.BRIDGE_NODE
    ) -> RosbridgeEndpoint:  # not bridge.…: the field `bridge` hides it
        """The rosbridge endpoint of either transport (the embedded bus or the DDS relay). A client's
        relative names resolve under ``namespace`` (the bridge node's; default --namespace), ``~``
        under ``node``, as rosbridge_suite's node resolves them."""
        ns = self.namespace if namespace is None else namespace
        resolve = Exposure(namespace=ns, node=node).resolve  # as the endpoint's own: one definition

        expose = TopicFilter.parse(self.topics_glob, None) if self.topics_glob else None
        services = TopicFilter.parse(self.services_glob, None) if self.services_glob else None
        params = TopicFilter.parse(self.params_glob, None) if self.params_glob else None
        param_ok = params.wants if params else lambda name: True
        # no graph on the embedded transport: its parameters live in a store in memory
        rosapi_services = rosapi.ParamStore().handlers(param_ok)
        graph = getattr(bus, "graph", None)
        if graph is not None:  # rosapi from the live graph where there is one (ROS mode)
            rosapi_services = rosapi.handlers(
                graph,
                topic_ok=expose.wants if expose else lambda name: True,
                service_ok=services.wants if services else lambda name: True,
                param_ok=param_ok,
                resolve=resolve,
            )
        return bridge.RosbridgeEndpoint(
            bus,
            token=self.token,
            heartbeat=self.ws_ping or None,
            paced_wait=self.paced_wait or None,
            max_frame=self.max_frame,
            services=rosapi_services,
            expose_topics=expose,
            expose_services=services,
            expose_actions=TopicFilter.parse(self.actions_glob, None) if self.actions_glob else None,
            namespace=ns,
            node=node,
        )

    def make_topic_watch(self) -> TopicWatch:
        return TopicWatch(TopicFilter.parse(self.topics_include, self.topics_exclude), self.topics_window)

    def ssl_context(self) -> ssl.SSLContext | None:
        if self.tls_cert is None:
            return None
        ctx = ssl.create_default_context(ssl.Purpose.CLIENT_AUTH)
        ctx.load_cert_chain(str(self.tls_cert), None if self.tls_key is None else str(self.tls_key))
        return ctx

    def make_tracker(self) -> LatencyTracker:
        return LatencyTracker(
            deploy_mode=self.deploy_mode,
            max_records=self.max_records,
            cmd_timeout=self.cmd_timeout,
            limits=self.limits,
            max_command_age_ms=self.max_command_age_ms,
        )

    def make_simulator(self) -> DiffDriveSimulator:
        return DiffDriveSimulator(self.limits, cmd_timeout=self.cmd_timeout)


class Servers:
    """The two listening sockets every transport has: the rosbridge endpoint and the tracker's HTTP API."""

    def __init__(self, config: BackendConfig) -> None:
        self.config = config
        self._runners: list[web.AppRunner] = []
        self.bridge_port: int | None = None
        self.api_port: int | None = None
        self.sim_enabled = False
        self._ssl = config.ssl_context()
        # the host's clock-sync probe, cached: one for the API's /api/health and the fleet's announcer
        self.host_clock = HostClock()
        # every long-lived worker of the backend, whichever the transport (supervise.py)
        self.supervisor = Supervisor()
        # with --zenoh, the fleet link's state for /api/health (set by the command line before start)
        self.fleet_health: Callable[[], dict[str, Any]] | None = None

    async def _serve(self, app: web.Application, port: int) -> int:
        runner = web.AppRunner(app, access_log=None, handle_signals=False)
        await runner.setup()
        self._runners.append(runner)
        site = web.TCPSite(runner, self.config.host, port, reuse_address=True, ssl_context=self._ssl)
        await site.start()
        server = site._server
        assert server is not None and server.sockets  # type: ignore[attr-defined]  # the loop's Server
        return int(server.sockets[0].getsockname()[1])  # type: ignore[attr-defined]  # the loop's Server

    async def start_servers(
        self,
        endpoint: bridge.RosbridgeEndpoint | None,
        tracker: LatencyTracker,
        topics: api.TopicSource | None = None,
        autonomy: api.AutonomySource | None = None,
    ) -> None:
        # Here, not in the CLI: in ROS mode a parameter may have changed the host.
        auth.check_exposure(self.config.host, self.config.allow_remote, self.config.token)
        try:
            if endpoint is not None:
                self.bridge_port = await self._serve(bridge.make_app(endpoint), self.config.bridge_port)
            api_app = api.make_app(
                tracker,
                self.config.token,
                topics,
                host_clock=self.host_clock,
                bridge=endpoint.stats if endpoint is not None else None,
                autonomy=autonomy,
                workers=self.supervisor.workers,
                fleet=self.fleet_health,
            )
            self.api_port = await self._serve(api_app, self.config.api_port)
        except BaseException:
            await self.stop_servers(endpoint)
            raise

    async def stop_servers(self, endpoint: bridge.RosbridgeEndpoint | None) -> None:
        if endpoint is not None:
            await endpoint.close_all()
        for runner in self._runners:
            await runner.cleanup()
        self._runners.clear()

    def describe(self) -> str:
        """The "listening" line (``arbiter_core.listening``) that tells a parent process the ports."""
        return format_listening(
            self.config.host,
            self.bridge_port,
            self.api_port,  # type: ignore[arg-type]  # set by start_servers, before anyone asks
            secure=self._ssl is not None,
            deploy_mode=self.config.deploy_mode,
            sim="on" if self.sim_enabled else "off",
            transport=self.config.transport,
            auth="token" if self.config.token else "none",
        )


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
