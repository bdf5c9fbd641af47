"""The rosbridge link: stamped commands out, odometry and latency reports in (roslibpy, Twisted thread)."""

from __future__ import annotations

import contextlib
import json
import logging
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from arbiter_core import envelope, topics
from arbiter_core import failures as errors

from ..analytics.observe import Observer
from . import twisted_internals
from .base import CLOSED, CONNECTED, CONNECTING, DISCONNECTED, RECONNECTING, Telemetry
from .observed import (
    TYPE_GOAL_STATUS_ARRAY,
    TYPE_PATH,
    TYPE_POSE_STAMPED,
    TYPE_TWIST,
    TYPE_TWIST_STAMPED,
    observe_command,
    observe_goal,
    observe_goal_status,
    observe_odometry,
    observe_plan,
)
from .streams import Streams

log = logging.getLogger(__name__)

MAX_RECONNECT_DELAY_S = 2.0
AUTH_RETRY_S = 30.0  # a rejected token is retried this slowly: it will be rejected again
PING_INTERVAL_S = 1.0  # WebSocket keep-alive: a ping every second...
ECHO_THROTTLE_MS = 500  # the topics screen's echo: at most 2 messages a second
PING_TIMEOUT_S = 2.0  # ...and a link with no pong for this long is dropped (then reconnected)
REPORT_QUEUE = 1000  # latency reports the server may hold for us (its default): 10 s of 100 Hz commands


class RosLink:
    """The rosbridge link: stamped commands out, odometry and latency reports in (roslibpy on Twisted's
    thread; its callbacks only write :class:`Telemetry`)."""

    def __init__(
        self,
        host: str,
        port: int,
        odom_throttle_ms: int = 50,
        token: str | None = None,
        path: str = "/",
        secure: bool = False,
        ca_file: Path | None = None,
        namespace: str = "",
        odom_topic: str = topics.ODOM,
    ) -> None:
        from roslibpy.comm import select_factory
        from twisted.internet import reactor
        from twisted.internet.threads import blockingCallFromThread

        twisted_internals.install()  # whether commands may go straight into the socket (this release)
        factory_cls = select_factory()
        factory_cls.set_max_delay(MAX_RECONNECT_DELAY_S)  # roslibpy's default is an hour
        factory_cls.set_initial_delay(0.3)
        self.telemetry = Telemetry()
        self._lock = threading.Lock()
        self._state = CONNECTING
        self._seq = 0
        self._zero_first = False
        self._ever_connected = False
        self._error: str | None = None
        self._odom_problem: str | None = None  # what the server said when it refused our odometry
        self._zero_pubs: dict[tuple[str, str], Any] = {}  # a stop's zero velocity, by (topic, type)
        self._reactor: Any = reactor
        # relative names resolve under the namespace, absolute ones are used as given (ROS rules)
        self.topic_stamped = topics.resolve(topics.STAMPED, namespace)
        self.topic_report = topics.resolve(topics.REPORT, namespace)
        self.topic_odom = topics.resolve(odom_topic, namespace)
        self.namespace = namespace
        host_part = f"[{host}]" if ":" in host else host
        self.url = f"{'wss' if secure else 'ws'}://{host_part}:{port}{path or '/'}"
        self._tls = tls_options(host, ca_file) if secure else None
        # Build on the reactor thread when it already runs (a second link in one process): the
        # connection attempt is queued behind this call, so the ping options and the event hooks
        # are in place before the first connection is made. Otherwise the reactor starts below.
        if reactor.running:
            blockingCallFromThread(reactor, self._build, token, odom_throttle_ms)
        else:
            self._build(token, odom_throttle_ms)
        self.ros.factory.manager.run()  # start the reactor thread without blocking on the connection

    def _build(self, token: str | None, odom_throttle_ms: int) -> None:
        import roslibpy

        # The token goes in the handshake's Authorization header: sent on every reconnect, before any
        # frame, and never part of a URL that could be logged. (Plain ws:// to another machine with a
        # token is refused before a link is made: arbiter_core.urls.check_token_transport.)
        headers = None if token is None else {"Authorization": f"Bearer {token}"}
        # A whole URL with port=None is used as given by roslibpy: scheme, host, port and path kept.
        self.ros = make_ros(self.url, headers, self._tls)
        factory = self.ros.factory
        # A silently dead link (cable out, Wi-Fi gone, NAT timeout) sends no FIN: only pings find it.
        factory.setProtocolOptions(autoPingInterval=PING_INTERVAL_S, autoPingTimeout=PING_TIMEOUT_S)

        def started() -> None:
            with self._lock:
                if self._state == DISCONNECTED:
                    self._state = RECONNECTING

        def failed(reason: Any) -> None:  # refused or unreachable: no "close" event
            with self._lock:
                if self._state != CLOSED:
                    self._state = DISCONNECTED
            value = getattr(reason, "value", reason)
            self._set_error(errors.connect_failure(type(value).__name__, str(value)))

        def lost(reason: Any) -> None:  # a TLS handshake that failed ends up here
            value = getattr(reason, "value", reason)
            if "SSL" in type(value).__module__ + type(value).__name__:
                self._set_error(errors.connect_failure(type(value).__name__, str(value)))

        twisted_internals.hook_connection(factory, started, failed, lost)
        link = self

        class Protocol(factory.protocol):  # type: ignore[misc, name-defined]  # roslibpy's, untyped
            def connectionMade(self) -> None:
                # commands are small and must leave at once: no Nagle (also under TLS)
                for layer in (self.transport, getattr(self.transport, "transport", None)):
                    if layer is not None and hasattr(layer, "setTcpNoDelay"):
                        with contextlib.suppress(Exception):
                            layer.setTcpNoDelay(True)
                        break
                super().connectionMade()

            def onClose(self, wasClean: bool, code: int | None, reason: str | None) -> None:
                said = errors.close_failure(code, reason)
                if said is not None:
                    link._set_error(said)
                    if said.startswith(errors.TOKEN_HINT):
                        # the same token will be refused again: retry slowly, and say so
                        twisted_internals.retry_slowly(factory, AUTH_RETRY_S)
                super().onClose(wasClean, code, reason)

        factory.protocol = Protocol
        factory.on("ready", self._on_ready)
        self.ros.on("close", self._on_close)
        self._cmd = roslibpy.Topic(self.ros, self.topic_stamped, topics.TYPE_STRING, queue_size=1)
        self._cmd.advertise()
        # Every stream the console takes goes through one registry (streams.py): one server
        # subscription per topic, any number of listeners, none removing another's.
        self.streams = Streams(
            self._write_frame,
            attach=self.ros.on,
            detach=self.ros.off,
            call_later=self._reactor.callLater,
        )
        self.streams.listen(
            self.topic_odom, topics.TYPE_ODOM, self.telemetry.set_odom, odom_throttle_ms, queue_length=1
        )
        # every report: one dropped by the server's queue counts its command lost for good (a link that
        # stalls delivers a burst of commands, and so of reports: 10 kept only the newest 10 of it)
        self.streams.listen(
            self.topic_report, topics.TYPE_STRING, self.telemetry.set_report, queue_length=REPORT_QUEUE
        )

    def _write_frame(self, frame: dict[str, Any]) -> None:
        """Send one rosbridge frame of the registry on the reactor thread (now when called there);
        dropped while the link is down: the registry sends its subscriptions again when it is up."""

        def write() -> None:
            proto = twisted_internals.open_protocol(self.ros.factory)
            if proto is None or not self.ros.is_connected:
                return
            try:
                proto.sendMessage(json.dumps(frame).encode("utf-8"), isBinary=False)
            except Exception:  # a socket closing under us: the next "ready" sends it again
                log.debug("sending %s failed", frame.get("op"), exc_info=True)

        if self._on_reactor_thread():
            write()
        else:
            self._reactor.callFromThread(write)

    def _on_reactor_thread(self) -> bool:
        from twisted.python import threadable

        return bool(
            self._reactor.running and threadable.isInIOThread()  # type: ignore[no-untyped-call]  # Twisted's
        )

    def _set_error(self, text: str) -> None:
        with self._lock:
            self._error = text
        log.warning("rosbridge link %s: %s", self.url, text)

    @property
    def error(self) -> str | None:
        """Why the link is down, in words (None while it is up, or before it ever failed)."""
        with self._lock:
            return None if self._state == CONNECTED else self._error

    def _on_ready(self, proto: Any) -> None:
        # roslibpy has no handler for rosbridge "status" frames; ours records the message.
        twisted_internals.handle_op(proto, "status", self._on_status)
        twisted_internals.retry_fast(self.ros.factory, MAX_RECONNECT_DELAY_S)  # a token accepted
        with self._lock:
            self._error = None
            self._odom_problem = None  # subscribed again: what the server says now counts
        with self.telemetry.lock:
            self.telemetry.connected_at = time.monotonic()
        with self._lock:
            self._state = CONNECTED
            if self._ever_connected:
                self._zero_first = True
            self._ever_connected = True
        self.streams.connected()  # our subscriptions, to this (new) connection

    def _on_close(self, *args: Any) -> None:
        with self._lock:
            if self._state != CLOSED:
                self._state = DISCONNECTED
        # whatever comes back may be another robot's life (a backend restarted: its odometry at the
        # origin again): missions and the record's path never cross it
        self.telemetry.new_life("the link was lost")
        self.streams.disconnected()
        with self.telemetry.lock:
            self.telemetry.connected_at = None
        self.telemetry.meter.reset_pending(time.monotonic())  # in flight: never reported

    def _on_status(self, message: dict[str, Any]) -> None:
        text = str(message.get("msg", ""))[:200]
        log.warning("rosbridge status %s: %s", message.get("level", "?"), text)
        if self.topic_odom in text or self.topic_odom in str(message.get("id", "")):
            # the server refused our odometry subscription (e.g. the topic has another type): the status
            # line names this cause rather than only "no odometry"
            with self._lock:
                self._odom_problem = text.removeprefix("subscribe: ")

    @property
    def odometry_problem(self) -> str | None:
        """Why the server would not give us odometry, as it said it (None: it said nothing)."""
        with self._lock:
            return self._odom_problem

    @property
    def state(self) -> str:
        with self._lock:
            if self._state == CONNECTED and not self.ros.is_connected:
                return DISCONNECTED
            return self._state

    def send(self, v: float, w: float) -> bool:
        """Publish one stamped command; refuses (False) while not connected, so nothing is
        queued for a burst replay on reconnect. After a reconnect the first command is a zero."""
        if self.state != CONNECTED:
            return False
        with self._lock:
            zero_first, self._zero_first = self._zero_first, False
        if zero_first:
            self._publish(0.0, 0.0)
        self._publish(v, w)
        return True

    def _publish(self, v: float, w: float) -> None:
        with self._lock:
            seq = self._seq
            self._seq += 1
        self._reactor.callFromThread(self._write_command, v, w, seq)

    def _write_command(self, v: float, w: float, seq: int) -> None:
        """Runs on the reactor thread: stamp, then write the frame at once, as a browser's
        ``Date.now()`` + ``ws.send`` does. roslibpy would stamp on the caller's thread and then
        hop threads, putting the hand-off wait (up to the GIL switch interval while the UI
        renders) inside the measured latency."""
        proto = twisted_internals.open_protocol(self.ros.factory)
        if proto is None or not self.ros.is_connected:
            return  # dropped while queued: counted lost by nobody, never stamped
        # lets the tracker judge the command's age across clocks: the clock model's offset now
        est = self.telemetry.meter.offset(time.monotonic())
        mono = time.monotonic()
        now_ns = time.time_ns()
        offset = None if est is None else est.offset_ms
        text = envelope.build(v, w, seq=seq, clock_ns=lambda: now_ns, offset_ms=offset)
        frame = json.dumps(
            {"op": "publish", "id": f"cmd:{seq}", "topic": self.topic_stamped, "msg": {"data": text}},
            separators=(",", ":"),
        )
        try:
            twisted_internals.write_now(proto, frame.encode("utf-8"))
        except Exception:  # a socket closing under us: the meter counts it lost later
            log.debug("sending a command failed", exc_info=True)
        # After the write: nothing that takes a lock stands between the stamp and the socket. The
        # report cannot come first: it arrives on this (the reactor's) thread.
        self.telemetry.meter.on_send(seq, envelope.stamp_ms_from_ns(now_ns), mono)

    def echo(
        self, topic: str, type_name: str, callback: Callable[[dict[str, Any]], None]
    ) -> Callable[[], None]:
        """The topics screen's echo of ``topic``: at most one message every ``ECHO_THROTTLE_MS``. A
        topic the console already takes (odometry, latency reports) shares that stream, throttled on
        our side; any other gets a server subscription with rosbridge's ``throttle_rate`` and
        ``queue_length`` 1. Returns the function that removes this echo and nothing else."""
        return self.streams.listen(topic, type_name, callback, ECHO_THROTTLE_MS, queue_length=1)

    def observe(
        self,
        observer: Observer,
        cmd: str,
        cmd_stamped: bool,
        plan: str,
        goal: str,
        status: str | None = None,
    ) -> Callable[[], None]:
        """Feed ``observer`` from the robot's own topics (relative names under the namespace): odometry
        shares the console's stream; the command, plan, goal and the action's goal status are streams of
        their own. Every call comes on the link's thread, stamped with this host's clock. Returns the
        function that stops it."""
        ns = self.namespace
        removers = [
            self.streams.listen(self.topic_odom, topics.TYPE_ODOM, lambda m: observe_odometry(observer, m)),
            self.streams.listen(
                topics.resolve(cmd, ns),
                TYPE_TWIST_STAMPED if cmd_stamped else TYPE_TWIST,
                lambda m: observe_command(observer, m, cmd_stamped),
            ),
            self.streams.listen(topics.resolve(plan, ns), TYPE_PATH, lambda m: observe_plan(observer, m)),
            self.streams.listen(
                topics.resolve(goal, ns), TYPE_POSE_STAMPED, lambda m: observe_goal(observer, m)
            ),
        ]
        if status:
            statuses = topics.resolve(status, ns)
            listener = lambda m: observe_goal_status(observer, m)  # noqa: E731
            removers.append(self.streams.listen(statuses, TYPE_GOAL_STATUS_ARRAY, listener))

        def stop() -> None:
            for remove in removers:
                remove()

        return stop

    def call_service(
        self, service: str, args: dict[str, Any], timeout_s: float, done: Callable[[bool, Any], None]
    ) -> bool:
        """rosbridge ``call_service`` (roslibpy's pending-request table answers it), with the server
        bounding its own wait (``timeout``); False at once while the link is down (nothing is queued for
        a reconnect). ``done(True, values)`` or ``done(False, error text)`` on the reactor's thread."""
        import roslibpy

        if self.state != CONNECTED:
            return False
        ident = f"call_service:{service}:{self.ros.id_counter}"
        frame = {"op": "call_service", "id": ident, "service": service, "args": args, "timeout": timeout_s}
        try:
            # roslibpy hands a ServiceResponse (a UserDict): the caller gets plain JSON values
            self.ros.call_async_service(
                roslibpy.Message(frame),
                lambda values: done(True, _plain(values)),
                lambda error: done(False, error),
            )
        except Exception:  # a socket closing under us: the caller's wait ends it
            log.debug("call_service %s failed", service, exc_info=True)
            return False
        return True

    def publish_zero(self, topic: str, stamped: bool) -> bool:
        """One zero velocity command on ``topic`` (Twist, or TwistStamped stamped now), advertised on its
        first use; False while the link is down."""
        import roslibpy

        if self.state != CONNECTED:
            return False
        type_name = TYPE_TWIST_STAMPED if stamped else TYPE_TWIST
        with self._lock:
            pub = self._zero_pubs.get((topic, type_name))
            if pub is None:
                pub = self._zero_pubs[(topic, type_name)] = roslibpy.Topic(self.ros, topic, type_name)
        zero = topics.twist(0.0, 0.0)
        msg = zero if not stamped else {"header": {"stamp": topics.stamp(time.time_ns()), "frame_id": ""},
                                        "twist": zero}  # fmt: skip
        try:
            pub.publish(roslibpy.Message(msg))
        except Exception:
            log.debug("zero on %s failed", topic, exc_info=True)
            return False
        return True

    def close(self) -> None:
        with self._lock:
            self._state = CLOSED
        try:
            # a link that is down would otherwise go on reconnecting for the life of the process
            self._reactor.callFromThread(self.ros.factory.stopTrying)
            if self.ros.is_connected:
                self.ros.close(timeout=2)
        except Exception:  # closing a dead link must never take the app down
            log.debug("closing the rosbridge link failed", exc_info=True)


def _plain(values: Any) -> Any:
    """A roslibpy message or response (a UserDict) as the plain dict its JSON was."""
    data = getattr(values, "data", values)
    return dict(data) if isinstance(data, dict) else data


def tls_options(host: str, ca_file: Path | None) -> Any:
    """Twisted client TLS options that verify the server's certificate and name: against ``ca_file``
    (PEM, one or more certificates) when given, else the system's trust store."""
    from twisted.internet import ssl

    if ca_file is None:
        trust = ssl.platformTrust()  # type: ignore[no-untyped-call]  # Twisted's is not annotated
    else:
        pem = Path(ca_file).read_bytes()
        certs = [
            ssl.Certificate.loadPEM(b"-----BEGIN CERTIFICATE-----" + part)
            for part in pem.split(b"-----BEGIN CERTIFICATE-----")[1:]
        ]
        if not certs:
            raise ValueError(f"--ca-file {ca_file}: no PEM certificate in it")
        trust = ssl.trustRootFromCertificates(certs)  # type: ignore[no-untyped-call]  # Twisted's
    return ssl.optionsForClientTLS(host, trustRoot=trust)


def make_ros(url: str, headers: dict[str, str] | None, tls: Any) -> Any:
    """A ``roslibpy.Ros`` for ``url``. For wss://, its factory connects with ``tls`` (verifying the
    certificate and host name) from the very first attempt: roslibpy's own factory connects wss://
    without any verification, and ``Ros.__init__`` starts connecting before it could be changed, so
    the factory is made here (these three attributes are all ``Ros.__init__`` sets in roslibpy 2.1.0,
    pinned in pyproject.toml; tests/integration/test_urls_tls.py fails if verification is skipped)."""
    import roslibpy
    from roslibpy.comm import select_factory

    if tls is None:
        return roslibpy.Ros(url, port=None, headers=headers)
    from autobahn.twisted.websocket import connectWS

    base = select_factory()

    class VerifiedFactory(base):  # type: ignore[misc, valid-type]  # roslibpy's, chosen at run time
        def _connect(self) -> None:
            self.connector = connectWS(self, contextFactory=tls)

    ros = roslibpy.Ros.__new__(roslibpy.Ros)
    ros._id_counter = 0
    ros.factory = VerifiedFactory(url, headers=headers)
    ros.is_connecting = False
    ros.connect()
    return ros
