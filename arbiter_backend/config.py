"""The backend's configuration, whichever the transport (the embedded bus, ``server.py``, or rclpy nodes on
DDS, ``ros/``): the flags as one dataclass, and what either transport makes from them (the rosbridge
endpoint, the tracker, the simulator, the topic monitor, the TLS context)."""

from __future__ import annotations

import ssl
from dataclasses import dataclass, field
from pathlib import Path

from arbiter_core import topics
from arbiter_core.kinematics import DEFAULT_LIMITS, Limits
from arbiter_core.simulator import DiffDriveSimulator
from arbiter_core.topicstats import WINDOW_S

from . import bridge, rosapi
from .bridge import MAX_FRAME_BYTES, WS_PING_S, RosbridgeEndpoint
from .bridge.exposure import Exposure
from .bus import Bus, GraphBus
from .pacing import WAIT_S as PACED_WAIT_S
from .topicwatch import TopicFilter, TopicWatch
from .tracker import DEFAULT_MAX_COMMAND_AGE_MS, LatencyTracker


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
        if isinstance(bus, GraphBus):  # rosapi from the live graph where there is one (ROS mode)
            rosapi_services = rosapi.handlers(
                bus.graph,
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
