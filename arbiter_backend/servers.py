"""The two listening sockets every transport has (the rosbridge endpoint and the tracker's HTTP API), and
what every transport keeps beside them: the host's clock-sync probe and the supervisor of its workers."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from aiohttp import web

from arbiter_core import auth
from arbiter_core.hostclock import HostClock
from arbiter_core.listening import format_listening

from . import api, bridge
from .config import BackendConfig
from .supervise import Supervisor
from .tracker import LatencyTracker


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
