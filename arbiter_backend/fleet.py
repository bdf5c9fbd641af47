"""``arbiter-backend --zenoh ENDPOINT[,...]``: the robot announces itself to fleet consoles over Zenoh.

It opens one Zenoh session (client by default, or peer; TLS/QUIC where the endpoint says so, with the
files and user/password of ``--zenoh-config``), declares the liveliness token ``arbiter/<name>/alive``
and publishes the payloads of ``arbiter_core.fleet`` at that module's rates, read from the backend's own
state: the tracker, the topic monitor, the robot-side autonomy and the odometry. A queryable answers
``arbiter/<name>/history`` with the last minutes of them, another ``arbiter/<name>/stop`` (a fleet
console's stop: ``RobotStop``, its own section below). Nothing here subscribes: a robot never reads
another's keys.

The session is opened on a thread of its own and retried for ever: a robot started before its router
serves its console as soon as the router is up, and one whose router restarts comes back by itself.
Zenoh is imported only here (and only with ``--zenoh``): the backend without it needs no Zenoh.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Coroutine
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from arbiter_core import fleet, stopping, topics
from arbiter_core.cliargs import installed_distribution
from arbiter_core.hostclock import HostClock
from arbiter_core.kinematics import pose_of_odometry
from arbiter_core.mission import Phase
from arbiter_core.stats import percentile
from arbiter_core.topicstats import Expectation, TopicFigures

from .autonomy import AutonomyService
from .bus import Bus, GraphBus, TopicBus
from .supervise import Supervisor
from .topicwatch import TopicWatch
from .tracker import LatencyTracker

if TYPE_CHECKING:
    from .bridge import RosbridgeEndpoint
    from .config import BackendConfig
    from .rosapi import Graph

log = logging.getLogger(__name__)
TICK_S = 0.25  # the announcer's beat: what is due is published on it
SYNC_REFRESH_S = 30.0  # the host's clock-sync probe (it may take a second: off the loop)
DRIVER_RECENT_S = 1.0  # a command this recent says who drives
MODES = ("client", "peer")
WORKER = "fleet-announcer"  # its name among the backend's supervised workers


class FleetConfigError(Exception):
    """``--zenoh`` cannot be used as given: one line for the command line."""


@dataclass(frozen=True)
class FleetSettings:
    endpoints: tuple[str, ...]
    name: str
    mode: str = "client"
    lease_ms: int = fleet.DEFAULT_LEASE_MS
    config_file: Path | None = None
    expect: tuple[Expectation, ...] = ()
    advertise_host: str | None = None


def import_zenoh() -> Any:
    try:
        import zenoh
    except ImportError:
        installed = installed_distribution()  # the console's install or the robot's: theirs differ
        raise FleetConfigError(f"--zenoh {fleet.zenoh_missing(installed and installed[0])}") from None
    return zenoh


def zenoh_config(zenoh: Any, settings: FleetSettings) -> Any:
    """The session's ``zenoh.Config``: the user's file (auth, TLS, ...) with our flags over it."""
    try:
        if settings.config_file is not None:
            config = zenoh.Config.from_file(str(settings.config_file))
        else:
            config = zenoh.Config()
        values = fleet.session_settings(
            settings.mode,
            settings.endpoints,
            (),
            settings.lease_ms,
            own_file=settings.config_file is not None,
        )
        for path, value in values.items():
            config.insert_json5(path, json.dumps(value))
    except Exception as exc:  # zenoh.ZError: the file or a value is not a Zenoh config
        where = f"--zenoh-config {settings.config_file}" if settings.config_file else "--zenoh"
        raise FleetConfigError(f"{where}: {str(exc).splitlines()[0][:160]}") from None
    return config


# -- what the announcer reads of the backend --------------------------------------------------------
@dataclass
class Sources:
    """The backend's state, whichever transport: what the payloads are made of."""

    tracker: LatencyTracker
    watch: TopicWatch | None
    autonomy: AutonomyService | None
    odometry: Callable[[], dict[str, Any] | None]  # the last odometry message (rosbridge JSON), or None
    cmd_topic: str  # the robot's cmd_vel, resolved: commands there that are none of ours are "foreign"
    namespace: str
    mode: str
    token: bool
    secure: bool
    host: str
    bridge_port: int | None
    api_port: int | None


# -- what the fleet reads of a backend: one protocol both transports meet, and the capabilities one has
# (isinstance, never a name probed: cli.py hands either backend here, and the type check holds both to
# FleetBackend; the capabilities are stated for it below, in _capabilities) -----------------------------
class WatchesTopics(Protocol):
    @property
    def watch(self) -> TopicWatch: ...


class FleetBackend(Protocol):
    """A started backend, whichever the transport (``server.Backend``, ``ros.backend.RosBackend``)."""

    @property
    def config(self) -> BackendConfig: ...
    @property
    def tracker(self) -> LatencyTracker: ...
    @property
    def sim_enabled(self) -> bool: ...
    @property
    def bridge_port(self) -> int | None: ...
    @property
    def api_port(self) -> int | None: ...
    @property
    def host_clock(self) -> HostClock: ...
    @property
    def supervisor(self) -> Supervisor: ...
    @property
    def bus(self) -> Bus | None: ...
    @property
    def endpoint(self) -> RosbridgeEndpoint | None: ...
    @property
    def topics(self) -> WatchesTopics: ...
    def publish_zero(self) -> None: ...


@runtime_checkable
class RunsAutonomy(Protocol):
    """The embedded backend: its robot-side controller in process (None without ``--autonomy``)."""

    @property
    def autonomy(self) -> AutonomyService | None: ...
    @property
    def topic_odom(self) -> str: ...


class ServesAutonomy(Protocol):
    @property
    def service(self) -> AutonomyService: ...


class NamedNode(Protocol):
    def get_namespace(self) -> str: ...


@runtime_checkable
class RunsNodes(Protocol):
    """The ROS backend: the controller in its own node, and the tracker node's namespace as rcl resolved
    it (a ``--ros-args -r __ns:=/robot1`` remap)."""

    @property
    def autonomy_node(self) -> ServesAutonomy | None: ...
    @property
    def tracker_node(self) -> NamedNode: ...


if TYPE_CHECKING:
    from .ros.backend import RosBackend
    from .server import Backend

    def _capabilities(
        embedded: Backend, ros: RosBackend
    ) -> tuple[FleetBackend, FleetBackend, RunsAutonomy, RunsNodes]:
        """What sources_of finds by isinstance, stated for the type check: a rename fails it."""
        return embedded, ros, embedded, ros


def sources_of(backend: FleetBackend, advertise_host: str | None = None) -> Sources:
    """Read an embedded (``server.Backend``) or ROS (``ros.backend.RosBackend``) backend, started."""
    config = backend.config
    autonomy = backend.autonomy if isinstance(backend, RunsAutonomy) else None
    node = backend.autonomy_node if isinstance(backend, RunsNodes) else None
    if node is not None:
        autonomy = node.service
    last: dict[str, Any] = {}
    bus = backend.bus
    if isinstance(backend, RunsAutonomy) and isinstance(bus, TopicBus):  # the embedded bus: its taps
        odom_topic = backend.topic_odom

        def tap(topic: str, type_name: str, msg: dict[str, Any]) -> None:
            if topic == odom_topic:
                last["odom"] = msg

        bus.taps.append(tap)
    words = [config.transport, *(["sim"] if backend.sim_enabled else []), *(["autonomy"] if autonomy else [])]
    if config.deploy_mode != "native":
        words.append(config.deploy_mode)
    host = advertise_host or config.host
    if host in ("0.0.0.0", "::", ""):
        host = socket.gethostname()
    # ROS: the tracker node's namespace as rcl resolved it (a ``--ros-args -r __ns:=/robot1`` remap)
    if isinstance(backend, RunsNodes):
        namespace = backend.tracker_node.get_namespace().rstrip("/")
    else:
        namespace = config.namespace
    return Sources(
        tracker=backend.tracker,
        watch=backend.topics.watch,
        autonomy=autonomy,
        odometry=lambda: last.get("odom"),
        cmd_topic=topics.resolve("cmd_vel", namespace),
        namespace=namespace,
        mode=", ".join(words)[:40],
        token=config.token is not None,
        secure=config.tls_cert is not None,
        host=host,
        bridge_port=backend.bridge_port,
        api_port=backend.api_port,
    )


def _urls(src: Sources) -> tuple[str | None, str | None]:
    host = f"[{src.host}]" if ":" in src.host else src.host
    ws, http = ("wss", "https") if src.secure else ("ws", "http")
    bridge = None if src.bridge_port is None else f"{ws}://{host}:{src.bridge_port}"
    api = None if src.api_port is None else f"{http}://{host}:{src.api_port}"
    return bridge, api


def _r(v: float | None, places: int = 3) -> float | None:
    return None if v is None else round(float(v), places)


class Announcer:
    """Builds the payloads from the backend's state and says which are due; keeps the history. No Zenoh
    and no event loop: the clocks are passed in (``now``: wall seconds, ``mono``: monotonic seconds)."""

    def __init__(self, settings: FleetSettings, src: Sources, started: float, host_clock: HostClock) -> None:
        self.settings = settings
        self.src = src
        self.started = started
        self.host_clock = host_clock
        self.name = settings.name
        self._due = dict.fromkeys((fleet.STATUS, fleet.LATENCY, fleet.TOPICS), 0.0)
        self._figures: list[TopicFigures] = []
        self._monitor: str | None = None  # why the figures' states are unknown (read with them)
        self._graded: object = None  # the last run graded (a Mission value)
        self.runs = 0
        self._run: fleet.RunGrade | None = None  # ended, not sent yet
        self._runs_sent = -1e9
        self._history: deque[tuple[float, fleet.Payload]] = deque()
        self._history_at = dict.fromkeys(fleet.KINDS, -1e9)
        self._lock = threading.Lock()  # the history is read on Zenoh's thread (queries)

    def restart(self) -> None:
        """Everything due at once (the session has just opened)."""
        self._due = dict.fromkeys(self._due, 0.0)

    # -- who drives -------------------------------------------------------------------------------
    def driver(
        self, mono: float, now: float, figures: list[TopicFigures] | None = None
    ) -> tuple[str, str | None]:
        """Who drives: a robot-side run, a console's commands, a foreign controller's on ``cmd_vel``
        (in ``figures``, a fresh snapshot; default the last payload's), or nobody."""
        svc = self.src.autonomy
        mission = None if svc is None else svc.autonomy.mission
        if mission is not None and (
            mission.running or (mission.ended_ms is not None and now * 1e3 - mission.ended_ms < 1e3)
        ):
            return "robot", f"{mission.algorithm} on {mission.name}"[:120]
        since = self.src.tracker.health()["seconds_since_last_command"]
        if since is not None and since < DRIVER_RECENT_S:
            return "console", f"last command {since * 1e3:.0f} ms ago"
        for f in self._figures if figures is None else figures:
            if f.name == self.src.cmd_topic and f.age_ms is not None and f.age_ms < DRIVER_RECENT_S * 1e3:
                rate = "" if f.rate_hz is None else f" at {f.rate_hz:.3g} Hz"
                return "foreign", f"commands on {f.name}{rate}"[:120]
        return "nobody", None if since is None else f"last command {since:.0f} s ago"

    # -- the payloads -----------------------------------------------------------------------------
    def status(self, mono: float, now: float) -> fleet.Status:
        if self.src.watch is not None:
            self._figures, self._monitor = self.src.watch.snapshot()
        driver, detail = self.driver(mono, now)
        svc = self.src.autonomy
        mission = None if svc is None else svc.autonomy.mission
        pose = velocity = None
        odom = self.src.odometry()
        if odom is not None:
            with contextlib.suppress(KeyError, TypeError, ValueError):
                p = pose_of_odometry(odom)
                pose = (round(p.x, 3), round(p.y, 3), round(p.theta, 3))
                tw = odom["twist"]["twist"]
                velocity = (round(float(tw["linear"]["x"]), 3), round(float(tw["angular"]["z"]), 3))
        elif svc is not None and svc.pose is not None:
            pose = (round(svc.pose.x, 3), round(svc.pose.y, 3), round(svc.pose.theta, 3))
        bridge, api = _urls(self.src)
        return fleet.Status(
            robot=self.name,
            t=round(now, 3),
            started=round(self.started, 3),
            driver=driver,
            driver_detail=detail,
            mode=self.src.mode,
            auth="token" if self.src.token else "none",
            controller=None if mission is None else mission.algorithm[:40],
            mission=None if mission is None else mission.name[:40],
            run_state=None if mission is None else mission.phase.value,
            waypoint=None if mission is None else mission.reached,
            waypoints=None if mission is None else mission.total,
            pose=pose,
            velocity=velocity,
            rosbridge=bridge,
            tracker=api,
            namespace=self.src.namespace or None,
            runs=self.runs,
            lease_ms=self.settings.lease_ms,
        )

    def latency(self, now: float) -> fleet.Latency:
        lat = self.src.tracker.window_latencies()
        health = self.src.tracker.health()
        sync = self.host_clock.cached()
        n = int(lat.size)
        return fleet.Latency(
            robot=self.name,
            t=round(now, 3),
            count=n,
            total=health["total_seen"],
            p50_ms=_r(percentile(lat, 0.5)) if n else None,
            p95_ms=_r(percentile(lat, 0.95)) if n else None,
            max_ms=_r(float(lat.max())) if n else None,
            stale=health["stale"],
            rejected=health["rejected"],
            sync_source=sync.source if sync is not None else "unknown",
            sync_ok=sync.synchronised if sync is not None else None,
            sync_error_ms=_r(sync.error_ms) if sync is not None and sync.error_ms is not None else None,
        )

    def topics(self, now: float) -> fleet.Topics | None:
        if self.src.watch is None:
            return None
        window = self.src.watch.window_s
        return fleet.topics_payload(
            self.name, round(now, 3), window, self._figures, self.settings.expect, self._monitor
        )

    def grade_runs(self, now: float) -> None:
        """A robot-side run that ended since the last look: graded once, counted, sent when the gap
        allows (a second one ending within the gap replaces the first in the payload; the count has
        both)."""
        svc = self.src.autonomy
        mission = None if svc is None else svc.autonomy.mission
        if mission is None or mission.running or mission is self._graded or mission.ended_ms is None:
            return
        self._graded = mission
        self.runs += 1
        final = svc.autonomy.final_error_m if mission.phase is Phase.COMPLETED and svc is not None else None
        self._run = fleet.RunGrade(
            n=self.runs,
            controller=mission.algorithm[:40],
            mission=mission.name[:40],
            outcome=mission.phase.value if mission.phase.value in fleet.OUTCOMES else "aborted",
            time_s=round(max(0.0, mission.time_s()), 2),
            reached=mission.reached,
            waypoints=mission.total,
            final_error_m=_r(final),
            ended=round(mission.ended_ms / 1e3, 3),
        )

    def due(self, mono: float, now: float) -> list[fleet.Payload]:
        """The payloads to publish now, and remembered for the history."""
        self.grade_runs(now)
        out: list[fleet.Payload] = []
        if mono >= self._due[fleet.STATUS]:
            out.append(self.status(mono, now))
            self._due[fleet.STATUS] = mono + fleet.STATUS_PERIOD_S
        if mono >= self._due[fleet.LATENCY]:
            out.append(self.latency(now))
            self._due[fleet.LATENCY] = mono + fleet.LATENCY_PERIOD_S
        if mono >= self._due[fleet.TOPICS]:
            t = self.topics(now)
            if t is not None:
                out.append(t)
            self._due[fleet.TOPICS] = mono + fleet.TOPICS_PERIOD_S
        if self._run is not None and mono - self._runs_sent >= fleet.RUNS_MIN_GAP_S:
            out.append(fleet.Runs(self.name, round(now, 3), self.runs, self._run))
            self._run, self._runs_sent = None, mono
        for p in out:
            self.remember(p, now)
        return out

    # -- history ----------------------------------------------------------------------------------
    THIN = {fleet.STATUS: fleet.HISTORY_STATUS_S, fleet.TOPICS: fleet.HISTORY_TOPICS_S}

    def remember(self, p: fleet.Payload, now: float) -> None:
        if now - self._history_at[p.kind] < self.THIN.get(p.kind, 0.0):
            return
        self._history_at[p.kind] = now
        with self._lock:
            self._history.append((now, p))
            while self._history and now - self._history[0][0] > fleet.HISTORY_MINUTES * 60:
                self._history.popleft()

    def history(self, minutes: float, now: float) -> bytes:
        """The history answer's bytes: the payloads of the last ``minutes``, as many of the newest as
        fit its size limit."""
        with self._lock:
            entries = [p for at, p in self._history if now - at <= minutes * 60]
        while True:
            answer = fleet.History(self.name, round(now, 3), minutes, tuple(entries))
            try:
                return fleet.encode(answer)
            except ValueError:
                entries = entries[len(entries) // 4 + 1 :]


# -- the Zenoh side ---------------------------------------------------------------------------------
UNREACHED_S = 3.0  # a session not open this long (no router answers): said once in the log
POLL_S = 1.0  # how often the open session's routers and peers are looked at


class LinkHealth:
    """The link's state, as ``/api/health`` shows it (its ``fleet`` key) and the log says it (once, then
    at each change): ``connecting`` (the session is being opened; Zenoh retries for ever), ``connected``
    (a router, or in peer mode a peer, is reached), ``retrying`` (the open session lost every one of
    them: Zenoh reconnects), ``failed`` (the session could not be opened), each since when; the last
    error. Written on the opening thread and the event loop, read on the loop."""

    def __init__(self, endpoints: tuple[str, ...], mode: str, now: float) -> None:
        self.where = f"{','.join(endpoints)} (Zenoh {mode})"
        self._endpoints, self._mode = list(endpoints), mode
        self._lock = threading.Lock()
        self.state, self.since = "connecting", now
        self.last_error: str | None = None
        self._started = now
        self._warned = False

    def to_dict(self) -> dict[str, Any]:
        with self._lock:
            return {
                "state": self.state,
                "since": round(self.since, 3),
                "endpoints": self._endpoints,
                "mode": self._mode,
                "last_error": self.last_error,
            }

    def failed(self, error: str, now: float) -> None:
        with self._lock:
            self.state, self.since, self.last_error = "failed", now, error

    def observe(self, reached: bool | None, now: float) -> None:
        """``reached``: whether the open session has a router or peer (None: not open yet). Logs a
        router not reached (once), reached, lost and reached again."""
        with self._lock:
            was = self.state
            if was == "failed":
                return
            if reached is None:
                if now - self._started >= UNREACHED_S and not self._warned:
                    self._warned = True
                    self.last_error = f"no router answered in {UNREACHED_S:g} s"
                    log.warning("fleet: cannot reach %s yet: retrying (/api/health: fleet)", self.where)
                return
            state = "connected" if reached else "retrying"
            if state == was:
                return
            self.state, self.since = state, now
            if state == "retrying":
                self.last_error = "lost every router and peer"
                self._warned = True
                log.warning("fleet: lost %s: retrying", self.where)
            elif self._warned:
                log.warning("fleet: reached %s after %.0f s", self.where, now - self._started)
            else:
                log.info("fleet: reached %s", self.where)


class FleetLink:
    """The robot's Zenoh session: opened on its own thread (retried for ever), then the token, one
    publisher per payload, the history queryable. ``put`` before it is open does nothing."""

    def __init__(self, settings: FleetSettings) -> None:
        self.settings = settings
        self.zenoh = import_zenoh()
        self.config = zenoh_config(self.zenoh, settings)
        self.session: Any = None
        self.opened = threading.Event()
        self.sent_bytes = dict.fromkeys(fleet.KINDS, 0)
        self._keep: list[Any] = []
        self._closed = False
        self._history: Callable[[float], bytes] | None = None
        self._stop: Callable[[Any], None] | None = None
        self.health = LinkHealth(settings.endpoints, settings.mode, time.time())
        self._polled = 0.0

    def open_in_background(
        self, history: Callable[[float], bytes], stop: Callable[[Any], None] | None = None
    ) -> None:
        self._history, self._stop = history, stop
        threading.Thread(target=self._open, name="zenoh-open", daemon=True).start()

    def _open(self) -> None:
        name = self.settings.name
        try:
            session = self.zenoh.open(self.config)
        except Exception as exc:
            error = str(exc).splitlines()[0][:160] if str(exc) else type(exc).__name__
            self.health.failed(error, time.time())
            log.error("fleet: cannot open a Zenoh session on %s: %s", self.health.where, error)
            return
        if self._closed:
            session.close()
            return
        self._publishers = {k: session.declare_publisher(fleet.key(name, k)) for k in fleet.KINDS}
        self._keep = [
            session.liveliness().declare_token(fleet.key(name, fleet.ALIVE)),
            session.declare_queryable(fleet.key(name, fleet.HISTORY), self._on_query),
        ]
        if self._stop is not None:
            self._keep.append(session.declare_queryable(fleet.key(name, fleet.STOP), self._stop))
        self.session = session
        self.opened.set()
        log.info("fleet: announcing as %s on %s", name, ",".join(self.settings.endpoints))

    def poll(self, mono: float) -> None:
        """The link's health brought up to date (on the announcer's beat, at most every ``POLL_S``)."""
        if mono - self._polled < POLL_S:
            return
        self._polled = mono
        reached = None
        if self.opened.is_set() and not self._closed:
            try:
                info = self.session.info
                reached = bool(list(info.routers_zid())) or (
                    self.settings.mode == "peer" and bool(list(info.peers_zid()))
                )
            except Exception as exc:  # the session closing
                log.debug("fleet: the session's routers not read: %s", exc)
                return
        self.health.observe(reached, time.time())

    def _on_query(self, query: Any) -> None:
        """A history query (on Zenoh's thread): answered, never raised out of."""
        try:
            assert self._history is not None
            minutes = fleet.history_minutes(str(query.parameters))
            query.reply(fleet.key(self.settings.name, fleet.HISTORY), self._history(minutes))
        except Exception as exc:
            log.warning("fleet: history query not answered: %s", exc)

    def put(self, kind: str, data: bytes) -> None:
        if not self.opened.is_set() or self._closed:
            return
        self._publishers[kind].put(data)
        self.sent_bytes[kind] += len(data)

    def close(self) -> None:
        self._closed = True
        if self.session is not None:
            with contextlib.suppress(Exception):
                for item in self._keep:
                    item.undeclare()
                self.session.close()


class FleetAnnouncer:
    """The announcer on the backend's event loop, publishing through the link."""

    def __init__(self, backend: FleetBackend, settings: FleetSettings, link: FleetLink) -> None:
        self.link = link
        self.backend = backend
        self.host_clock: HostClock = backend.host_clock  # the API's: the host is probed once for both
        self.supervisor: Supervisor = backend.supervisor  # the backend's: its workers in /api/health
        src = sources_of(backend, settings.advertise_host)
        self.announcer = Announcer(settings, src, time.time(), self.host_clock)
        self._task: asyncio.Task[None] | None = None
        self.robot_stop: RobotStop | None = None

    def start(self) -> None:
        stop = RobotStop(self.backend, self.announcer, asyncio.get_running_loop())
        self.robot_stop = stop
        self.link.open_in_background(lambda minutes: self.announcer.history(minutes, time.time()), stop.ask)
        self._task = self.supervisor.task(WORKER, self._run)

    async def _run(self) -> None:
        """The announcer's loop, supervised (``supervise.py``): an error that ends it (a bug: the payloads
        are pure) is logged once and the loop runs again, announcing afresh once the link is open."""
        loop = asyncio.get_running_loop()
        loop.run_in_executor(None, self.host_clock.read)
        synced, was_open = time.monotonic(), False
        while True:
            mono, now = time.monotonic(), time.time()
            if self.link.opened.is_set() and not was_open:
                was_open = True
                self.announcer.restart()
            if mono - synced > SYNC_REFRESH_S:
                synced = mono
                loop.run_in_executor(None, self.host_clock.read)
            self.supervisor.beat(WORKER)
            self.link.poll(mono)
            for p in self.announcer.due(mono, now):
                if was_open:
                    self.link.put(p.kind, fleet.encode(p))
            await asyncio.sleep(TICK_S)

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        if self.robot_stop is not None:
            self.robot_stop.close()
        await asyncio.to_thread(self.link.close)


# -- the stop a fleet console asks for (arbiter/<name>/stop) ------------------------------------------
class RobotStop:
    """A fleet console's stop, done in the robot's backend: first one zero command on the robot's command
    output, then the robot-side run aborted (its own zero), every goal of the foreign action servers there
    cancelled (``arbiter_core.stopping``: what the single-robot console's stop asks, asked from inside the
    robot), and when a foreign controller drove, zero velocity on its command topic for ``ZERO_FOR_S``.
    The answer (``fleet.StopAnswer``) says what it did, by ``fleet.STOP_ANSWER_S``: a cancel still under
    way is ``pending`` (and goes on). Asked on Zenoh's thread (:meth:`ask`), done on the backend's
    event loop, answered from there: Zenoh's thread never waits for it. Who may ask is the router's
    access control: the robot answers whoever reaches it."""

    def __init__(self, backend: FleetBackend, announcer: Announcer, loop: asyncio.AbstractEventLoop) -> None:
        self.backend = backend
        self.announcer = announcer
        self.loop = loop
        self.asked = 0
        self._tasks: set[asyncio.Task[Any]] = set()  # cancels and zeros that outlive their answer

    def ask(self, query: Any) -> None:
        """A stop query (Zenoh's thread): done on the loop, answered when done; never raised out of."""
        try:
            done = asyncio.run_coroutine_threadsafe(self.stop(), self.loop)
            done.add_done_callback(lambda f: self._answer(query, f))
        except Exception as exc:  # the loop is closing
            log.warning("fleet: a stop was not done: %s", exc)

    def _answer(self, query: Any, done: Any) -> None:
        try:
            answer = done.result()
            query.reply(fleet.key(self.announcer.name, fleet.STOP), fleet.encode(answer))
            log.warning("fleet: stopped by a fleet console: %s", answer.words())
        except Exception as exc:
            log.warning("fleet: a stop was not answered: %s", exc)
        finally:
            with contextlib.suppress(Exception):
                query.drop()  # the end of the answers, now

    async def stop(self) -> fleet.StopAnswer:
        """The zero first; then each step in its own try, so that none can keep the zero or the answer
        from going out; answered by ``fleet.STOP_ANSWER_S`` whatever is still under way."""
        self.asked += 1
        start = time.monotonic()
        zero = self._zero()
        cmd_topic = self.announcer.src.cmd_topic
        try:  # a fresh look at the topics: the announcer's figures may be a second old
            watch = self.announcer.src.watch
            figures = None if watch is None else watch.snapshot()[0]
            driver, detail = self.announcer.driver(time.monotonic(), time.time(), figures)
        except Exception as exc:
            log.warning("fleet: the stop could not tell who drives: %s", exc)
            driver, detail = "nobody", None
        try:
            actions = self._actions()
        except Exception as exc:
            log.warning("fleet: the stop could not list the action servers: %s", exc)
            actions = []
        cancelling = {a: self._keep(self._cancel(a)) for a in actions}  # they travel while the rest is done
        aborted = commands = None
        try:
            autonomy = self.announcer.src.autonomy
            said = {} if autonomy is None else autonomy.stop()  # its own zero goes out on the tracker's path
            if said.get("stopped"):
                at = f"{said['waypoint']}/{said['waypoints']}"
                aborted = f"{said['algorithm']} on {said['mission']} at {at}"
                commands = said["commands"]
        except Exception as exc:
            log.warning("fleet: the stop could not abort the robot-side run: %s", exc)
        left = max(0.0, fleet.STOP_ANSWER_S - (time.monotonic() - start))
        if cancelling:
            await asyncio.wait(cancelling.values(), timeout=left)
        cancels = tuple(self._cancel_of(a, task) for a, task in cancelling.items())
        try:
            if driver == "foreign" and self._cmd_type(cmd_topic) is not None:
                self._keep(self._foreign_zeros(cmd_topic))  # after the answer: a second of zeros
        except Exception as exc:
            log.warning("fleet: the stop's zeros on %s were not started: %s", cmd_topic, exc)
        still = None
        if driver == "console":  # its next command drives again: the fleet cannot stop a console
            still = f"a console drives ({detail})" if detail else "a console drives"
        elif driver == "foreign" and not any(c.outcome == "cancelled" for c in cancels):
            still = f"a foreign controller may ({detail})" if detail else "a foreign controller may"
        return fleet.StopAnswer(
            robot=self.announcer.name,
            t=round(time.time(), 3),
            driver=driver,
            zero=zero,
            aborted=None if aborted is None else aborted[:120],
            commands=commands,
            cancels=cancels,
            still=None if still is None else still[:120],
        )

    def _keep(self, work: Coroutine[Any, Any, Any]) -> asyncio.Task[Any]:
        """A task of the stop's that may outlive its answer: held until done, cancelled by :meth:`close`."""
        task = self.loop.create_task(work)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task

    @staticmethod
    def _cancel_of(action: str, task: asyncio.Task[stopping.ActionCancel]) -> fleet.StopCancel:
        """``action``'s cancel as the answer says it: its outcome, or ``pending`` (it goes on)."""
        if not task.done():
            return fleet.StopCancel(action, stopping.Cancel.PENDING.value)
        if task.cancelled() or task.exception() is not None:
            return fleet.StopCancel(action, stopping.Cancel.FAILED.value)
        c = task.result()
        return fleet.StopCancel(c.action, c.outcome.value, c.goals)

    def close(self) -> None:
        """The backend stops: the zeros and cancels still under way end."""
        for task in list(self._tasks):
            task.cancel()

    def _zero(self) -> bool:
        """One zero command on the robot's output (what the deadman sends), where the backend has one."""
        try:
            self.backend.publish_zero()
        except Exception as exc:
            log.warning("fleet: the stop's zero was not sent: %s", exc)
            return False
        return True

    def _graph(self) -> Graph | None:
        """The ROS graph the cancels go over: the endpoint's, or the bus's where no endpoint runs
        (``--transport ros --no-bridge``: the stock rosbridge_server beside it); None on the embedded bus."""
        endpoint = self.backend.endpoint
        if endpoint is not None:
            return endpoint.service_room.graph
        bus = self.backend.bus
        return bus.graph if isinstance(bus, GraphBus) else None

    def _actions(self) -> list[str]:
        """The action servers a stop cancels (Nav2's, under the robot's namespace) that are there: provided
        by a client of the endpoint, or on the ROS graph."""
        endpoint, graph = self.backend.endpoint, self._graph()
        ns = self.announcer.src.namespace
        wanted = [topics.resolve(a, ns, what="action") for a in stopping.NAV2_ACTIONS]
        on_graph: set[str] = set()
        if graph is not None:
            with contextlib.suppress(Exception):
                on_graph = {name for name, _ in graph.service_names_and_types()}
        provided = () if endpoint is None else endpoint.service_room.provided
        there = [a + stopping.CANCEL_SUFFIX for a in wanted]
        return [a for a, srv in zip(wanted, there, strict=True) if srv in provided or srv in on_graph]

    async def _cancel(self, action: str) -> stopping.ActionCancel:
        """Every goal of ``action`` cancelled: through the bridge's client that provides it, else on the
        ROS graph; bounded by ``CANCEL_TIMEOUT_S``."""
        endpoint, graph = self.backend.endpoint, self._graph()
        service = action + stopping.CANCEL_SUFFIX
        try:
            provided = None if endpoint is None else endpoint.service_room.provided.get(service)
            if provided is not None:
                ok, values = await provided.call(stopping.CANCEL_ALL, stopping.CANCEL_TIMEOUT_S)
                if not ok:
                    return stopping.cancel_failure(action, str(values))
            elif graph is None:
                return stopping.cancel_failure(action, "no provider and no ROS graph")
            else:
                call = graph.call_service(service, stopping.CANCEL_ALL)
                values = await asyncio.wait_for(call, stopping.CANCEL_TIMEOUT_S)
        except (TimeoutError, asyncio.TimeoutError):
            return stopping.cancel_failure(action, f"no answer in {stopping.CANCEL_TIMEOUT_S:g} s")
        except Exception as exc:
            return stopping.cancel_failure(action, str(exc) or type(exc).__name__)
        return stopping.cancel_outcome(action, values)

    def _cmd_type(self, cmd_topic: str) -> str | None:
        bus = self.backend.bus
        t = None if bus is None else bus.type_of(cmd_topic)
        return t if t in (topics.TYPE_TWIST, topics.TYPE_TWIST_STAMPED) else None

    async def _foreign_zeros(self, cmd_topic: str) -> None:
        """Zero velocity on the robot's ``cmd_vel`` at ``ZERO_HZ`` for ``ZERO_FOR_S`` (a controller still
        publishing there overrides it: the answer said so)."""
        kind = "twist_stamped" if self._cmd_type(cmd_topic) == topics.TYPE_TWIST_STAMPED else "twist"
        end = time.monotonic() + stopping.ZERO_FOR_S
        while time.monotonic() < end:
            try:
                zero = topics.measured_message(0.0, 0.0, kind, time.time_ns())
                bus = self.backend.bus
                if bus is None:
                    return
                bus.publish(cmd_topic, zero)
            except Exception as exc:
                log.warning("fleet: a zero on %s was not sent: %s", cmd_topic, exc)
                return
            await asyncio.sleep(1.0 / stopping.ZERO_HZ)


def settings_from_args(args: Any, namespace: str) -> FleetSettings | None:
    """The ``--zenoh`` flags checked (FleetConfigError in one line); None without ``--zenoh``."""
    from arbiter_core.topicstats import parse_expect

    if args.zenoh is None:
        for flag in ("robot_name", "zenoh_config", "expect", "advertise_host"):
            if getattr(args, flag) is not None:
                raise FleetConfigError(f"--{flag.replace('_', '-')} needs --zenoh ENDPOINT")
        return None
    try:
        endpoints = fleet.parse_endpoints(args.zenoh)
        name = (
            fleet.robot_name(args.robot_name)
            if args.robot_name is not None
            else fleet.default_name(namespace, socket.gethostname())
        )
        expect = tuple(parse_expect(args.expect)) if args.expect is not None else ()
    except ValueError as exc:
        flag = (
            "--robot-name" if "robot name" in str(exc) else "--expect" if "expect" in str(exc) else "--zenoh"
        )
        raise FleetConfigError(f"{flag}: {exc}") from None
    if args.zenoh_config is not None and not args.zenoh_config.is_file():
        raise FleetConfigError(f"--zenoh-config {args.zenoh_config}: no such file")
    return FleetSettings(
        endpoints=endpoints,
        name=name,
        mode=args.zenoh_mode,
        lease_ms=args.zenoh_lease,
        config_file=args.zenoh_config,
        expect=expect,
        advertise_host=args.advertise_host,
    )
