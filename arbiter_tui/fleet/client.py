"""The fleet console's Zenoh session: robots' tokens and payloads into a ``FleetModel``.

A client of the site's router (``--connect``), or the router itself (``--listen``, for a site with
none). It subscribes to ``arbiter/*/alive`` liveliness (with history: the robots already there are
listed at once) and to ``arbiter/*/*`` payloads, and asks ``arbiter/<name>/history`` on demand, and
``arbiter/<name>/stop`` when the person stops a robot (who may is the router's access control). The
payloads wait in Zenoh's queue and one thread of the console takes them in batches (``DRAIN_S``); each is
checked by ``arbiter_core.fleet.decode`` (its size before it is copied) outside the model's lock; the
model is then changed under the lock, and the screen takes frozen views. Nothing a robot sends can raise
out of that thread or a callback: it marks that robot's row, or is counted.

The only module of the console that imports Zenoh, and only when asked for (``import_zenoh``).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from arbiter_core import fleet
from arbiter_core.hostclock import HostClock

from . import memory
from .rows import FleetModel, FleetView, Row, clock_time

log = logging.getLogger(__name__)
SYNC_REFRESH_S = 30.0
TRIM_S = 10.0
HISTORY_TIMEOUT_S = 3.0
BACKFILL_WORKERS = 8  # history questions asked at once
BACKFILL_MINUTES = 1.0  # a robot first seen: its latest latency, topics and runs from its history
# payloads are taken in batches: Zenoh queues them (a ring: a flood beyond what Python can take drops the
# oldest there, the console's memory stays bounded and Zenoh's threads never wait on it), one thread
# takes what is queued this often. A callback per payload cost 3-4 times the CPU at 500 robots: a thread
# woken, the GIL taken and a cold interpreter for each of 850 payloads a second (bench/fleet.py)
DRAIN_S = 0.1
QUEUED = 16384  # payloads queued at most between two drains (~160,000 a second)
SHARED_MEMORY = "transport/shared_memory/enabled"  # off in the console (zenoh_config)
RUNTIME = "(acc: (handover: rx))"  # ZENOH_RUNTIME (import_zenoh)


class FleetUnavailable(Exception):
    """The fleet cannot run as asked: one line."""


def import_zenoh() -> Any:
    # Zenoh's accept runtime handed over to its rx runtime: a link accepted there had each of its packets
    # woken through the accept thread, a thread switch per payload (1-1.5 % of a core at 500 robots).
    # Read when Zenoh's runtime starts (the first session); a ZENOH_RUNTIME of the user's wins.
    os.environ.setdefault("ZENOH_RUNTIME", RUNTIME)
    try:
        import zenoh
    except ImportError:
        raise FleetUnavailable(f"arbiter-tui fleet {fleet.ZENOH_MISSING}") from None
    return zenoh


@dataclass(frozen=True)
class ConsoleSettings:
    connect: tuple[str, ...] = ()
    listen: tuple[str, ...] = ()
    config_file: Path | None = None
    # the console's own lease: how soon its robots and router drop *it* (Zenoh's default, 10 s). Not how
    # soon a robot reads "lost": that is the robot's lease. A short one here makes robots behind a lossy
    # link drop the console, and their tokens with it, at every burst of losses.
    lease_ms: int | None = None

    @property
    def mode(self) -> str:
        return "router" if self.listen else "client"

    def describe(self) -> str:
        if self.listen:
            more = f", connected to {','.join(self.connect)}" if self.connect else ""
            return f"router on {','.join(self.listen)}{more}"
        return f"client of {','.join(self.connect)}"


def zenoh_config(zenoh: Any, settings: ConsoleSettings, connect_timeout_ms: int | None = None) -> Any:
    """The session's config: the user's file (auth, TLS, ACL for a router) with the flags over it;
    ``connect_timeout_ms``: give up connecting after that long (``--json``), else retry for ever."""
    try:
        config = zenoh.Config.from_file(str(settings.config_file)) if settings.config_file else zenoh.Config()
        values = fleet.session_settings(
            settings.mode,
            settings.connect,
            settings.listen,
            settings.lease_ms,
            settings.config_file is not None,
        )
        # no shared memory: a robot on this host would send its big payloads (over 3 KB: nothing a
        # console reads, a topics payload is at most 4 KB) through a 16 MB pool of its own that this
        # process maps and keeps resident after they are dropped (bench/fleet_flood.py: +17 MB for good)
        values[SHARED_MEMORY] = False
        if connect_timeout_ms is not None and settings.connect:
            values["connect/timeout_ms"] = connect_timeout_ms
            values["connect/exit_on_failure"] = True
        for path, value in values.items():
            config.insert_json5(path, json.dumps(value))
    except Exception as exc:  # zenoh.ZError: not a Zenoh config
        where = f"--zenoh-config {settings.config_file}" if settings.config_file else "the Zenoh settings"
        raise FleetUnavailable(f"{where}: {str(exc).splitlines()[0][:160]}") from None
    return config


class FleetClient:
    def __init__(
        self,
        settings: ConsoleSettings,
        model: FleetModel | None = None,
        wall: Callable[[], float] = time.time,
        mono: Callable[[], float] = time.monotonic,
        host_clock: HostClock | None = None,
    ) -> None:
        self.settings = settings
        self.zenoh = import_zenoh()
        zenoh_config(self.zenoh, settings)  # a bad config file is one line now, not on the open thread
        self.model = model if model is not None else FleetModel()
        self.wall, self.mono = wall, mono
        self.host_clock = host_clock if host_clock is not None else HostClock()
        self.session: Any = None
        self.error: str | None = None
        self.opened = threading.Event()
        self._closed = threading.Event()
        self._lock = threading.Lock()
        self._keep: list[Any] = []
        self._routers: set[str] = set()  # the routers this client's session is connected to
        self._link_since: float | None = None  # wall s the link went up or down (as _routers says)
        self._asked: set[str] = set()  # robots whose history was asked when they first appeared
        self._pending = 0
        # the history questions, off Zenoh's threads: a few at a time (a console that starts beside
        # 200 robots hears all their tokens at once)
        self._backfills = ThreadPoolExecutor(BACKFILL_WORKERS, thread_name_prefix="fleet-backfill")

    # -- the session ------------------------------------------------------------------------------
    def open(self, connect_timeout_ms: int | None = None) -> None:
        """Open the session (blocking; as a client it waits for the router, for ever unless
        ``connect_timeout_ms``); FleetUnavailable in one line when it cannot."""
        config = zenoh_config(self.zenoh, self.settings, connect_timeout_ms)
        try:
            session = self.zenoh.open(config)
        except Exception as exc:
            first = str(exc).splitlines()[0]
            what = "listen on" if self.settings.listen else "reach the router at"
            where = ",".join(self.settings.listen or self.settings.connect)
            raise FleetUnavailable(f"cannot {what} {where}: {first.split(' at /')[0][:160]}") from None
        if self._closed.is_set():
            session.close()
            return
        # the session first: the tokens already there arrive while their subscriber is being declared,
        # and each new robot's history is asked on it at once
        self.session = session
        self._keep = [
            session.liveliness().declare_subscriber(
                fleet.key("*", fleet.ALIVE), self._on_token, history=True
            ),
            session.declare_subscriber(fleet.key("*", "*"), self.zenoh.handlers.RingChannel(QUEUED)),
        ]
        samples = self._keep[-1]
        if self.settings.mode == "client":  # its own link: to its router (a router has none of its own)
            with self._lock:
                self._link_since = self.wall()
            events = session.info.declare_transport_events_listener(self._on_transport, history=True)
            self._keep.append(events)
        self.opened.set()
        threading.Thread(target=self._sync_loop, name="fleet-clock", daemon=True).start()
        threading.Thread(target=self._drain_loop, args=(samples,), name="fleet-samples", daemon=True).start()

    def open_in_background(self) -> None:
        def run() -> None:
            try:
                self.open()
            except FleetUnavailable as exc:
                self.error = str(exc)

        threading.Thread(target=run, name="fleet-open", daemon=True).start()

    def close(self) -> None:
        self._closed.set()
        self._backfills.shutdown(wait=False, cancel_futures=True)
        if self.session is not None:
            with contextlib.suppress(Exception):
                for item in self._keep:
                    item.undeclare()
                self.session.close()

    def _sync_loop(self) -> None:
        """This host's clock sync (for the offset bounds), read now and every SYNC_REFRESH_S; the heap's
        free pages given back every TRIM_S (a flood's peak does not stay resident)."""
        synced: float | None = None
        while not self._closed.is_set():
            if synced is None or self.mono() - synced >= SYNC_REFRESH_S:
                synced = self.mono()
                sync = self.host_clock.read()
                with self._lock:
                    self.model.console_sync = sync
            memory.trim()
            self._closed.wait(TRIM_S)

    # -- what arrives (on Zenoh's threads) --------------------------------------------------------
    def _on_token(self, sample: Any) -> None:
        try:
            parsed = fleet.parse_key(str(sample.key_expr))
            if parsed is None or parsed[1] != fleet.ALIVE:
                with self._lock:
                    self.model.unknown_key()
                return
            present = sample.kind == self.zenoh.SampleKind.PUT
            with self._lock:
                first = parsed[0] not in self._asked and present
                self.model.token(parsed[0], present, self.wall(), self.mono())
                if first:
                    self._asked.add(parsed[0])
                    self._pending += 1
            if first:  # its figures now, not a topics period later
                try:
                    self._backfills.submit(self._backfill, parsed[0])
                except RuntimeError:  # closed meanwhile: nobody will ask
                    with self._lock:
                        self._pending -= 1
        except Exception:  # never out of a callback
            log.exception("fleet: a liveliness sample was not taken")

    def _on_transport(self, event: Any) -> None:
        """This client's link to a router opened or closed (Zenoh's thread): while none is open no robot
        is lost or alive, the rows say "unknown since" (``FleetModel.link``)."""
        try:
            zid = str(event.transport.zid)
            up = event.kind == self.zenoh.SampleKind.PUT
            with self._lock:
                was = bool(self._routers)
                if up:
                    self._routers.add(zid)
                else:
                    self._routers.discard(zid)
                if was != bool(self._routers):
                    self._link_since = self.wall()
                    self.model.link(bool(self._routers), self._link_since, self.mono())
        except Exception:  # never out of a callback
            log.exception("fleet: a transport event was not taken")

    def _backfill(self, name: str) -> None:
        try:
            answer = self.history(name, BACKFILL_MINUTES)
            if not isinstance(answer, str):
                with self._lock:
                    self.model.backfill(answer, self.mono())
        finally:
            with self._lock:
                self._pending -= 1

    def pending(self) -> int:
        """History questions asked of robots just seen and not answered yet."""
        with self._lock:
            return self._pending

    def _drain_loop(self, samples: Any) -> None:
        """What Zenoh queued on ``arbiter/*/*``, taken every DRAIN_S until the console closes."""
        while not self._closed.wait(DRAIN_S):
            self.drain(samples)

    def drain(self, samples: Any) -> int:
        """Every sample queued in ``samples`` (a subscriber with a channel) taken now; how many."""
        put = self.zenoh.SampleKind.PUT
        taken = 0
        while True:
            try:
                sample = samples.try_recv()
            except Exception:  # undeclared: the session closed meanwhile
                return taken
            if sample is None:
                return taken
            taken += 1
            try:
                self.take(str(sample.key_expr), sample.payload, sample.kind == put)
            except Exception:  # nothing a robot sends stops the others' being taken
                log.exception("fleet: a sample was not taken")

    def take(self, key: str, payload: Any, put: bool = True) -> None:
        """One sample on ``arbiter/*/*``: checked (its size before its bytes are copied), then into
        the model. ``payload``: Zenoh's ZBytes, or bytes."""
        parsed = fleet.parse_key(key)
        if parsed is None or parsed[1] not in fleet.KINDS or not put:
            if parsed is None or parsed[1] not in (fleet.HISTORY, fleet.ALIVE):
                with self._lock:
                    self.model.unknown_key()
            return
        name, kind = parsed
        with self._lock:  # over its kind's rate: dropped before a byte is copied or parsed
            if not self.model.admit(name, kind, self.mono()):
                return
        size = len(payload)
        try:
            if size > fleet.MAX_BYTES[kind]:
                raise fleet.FleetPayloadError(
                    f"{kind}: {fleet.size_words(size)}, over the {fleet.size_words(fleet.MAX_BYTES[kind])} "
                    f"a {kind} may be"
                )
            data = payload if isinstance(payload, bytes) else payload.to_bytes()
            decoded = fleet.decode(data, kind, name)
        except fleet.FleetPayloadError as exc:
            with self._lock:
                self.model.reject(name, str(exc), self.mono())
            return
        with self._lock:
            self.model.accept(decoded, size, self.mono())  # type: ignore[arg-type]  # kind in KINDS: Payload

    # -- what the screen asks ---------------------------------------------------------------------
    def session_words(self) -> str:
        """Where this console's session is, and for a client whether its link to the router is up:
        ``client of tcp/... · connected since 14:00:01`` / ``· reconnecting since 14:02:11``."""
        if self.error is not None:
            return self.error
        if not self.opened.is_set():
            return f"connecting: {self.settings.describe()}"
        if self.settings.mode != "client" or self._link_since is None:
            return self.settings.describe()
        link = "connected" if self._routers else "reconnecting"
        return f"{self.settings.describe()} · {link} since {clock_time(self._link_since)}"

    def view(self, pattern: str = "") -> FleetView:
        with self._lock:
            return self.model.view(self.wall(), self.mono(), pattern, self.session_words(), self.error)

    def row(self, name: str) -> Row | None:
        """One robot's row now (None: never heard of)."""
        with self._lock:
            return self.model.row_of(name, self.wall(), self.mono())

    def history(self, name: str, minutes: float = fleet.HISTORY_MINUTES) -> fleet.History | str:
        """The robot's answer to ``arbiter/<name>/history?minutes=N``, or why there is none (one line)."""
        if self.session is None:
            return "not connected"
        try:
            replies = self.session.get(
                f"{fleet.key(name, fleet.HISTORY)}?minutes={minutes:g}", timeout=HISTORY_TIMEOUT_S
            )
            for reply in replies:
                if reply.ok is None:
                    return f"{name} answered with an error"
                answer = fleet.decode(reply.ok.payload.to_bytes(), fleet.HISTORY, name)
                assert isinstance(answer, fleet.History)
                return answer
        except fleet.FleetPayloadError as exc:
            return f"{name}'s history: {exc}"
        except Exception as exc:
            return f"{name}'s history: {str(exc).splitlines()[0][:120]}"
        return f"{name} did not answer in {HISTORY_TIMEOUT_S:g} s"

    def stop(self, name: str) -> fleet.StopAnswer | str:
        """Ask ``name`` to stop whatever drives it (``arbiter/<name>/stop``): its answer, or why there is
        none, in one line. A query the router lets through to no robot ends at once with no answer:
        refused by its access control (or the robot is not there); a robot that took it and did not
        answer ends it after ``fleet.STOP_TIMEOUT_S``."""
        if self.session is None:
            return f"not stopped: not connected ({self.session_words()})"
        with self._lock:
            down = self.settings.mode == "client" and self._link_since is not None and not self._routers
        if down:
            return "not stopped: this console's link to its router is down (nothing was asked)"
        asked = self.mono()
        try:
            for reply in self.session.get(fleet.key(name, fleet.STOP), timeout=fleet.STOP_TIMEOUT_S):
                if reply.ok is None:
                    return f"not stopped: {name} answered with an error"
                answer = fleet.decode(reply.ok.payload.to_bytes(), fleet.STOP, name)
                assert isinstance(answer, fleet.StopAnswer)
                return answer
        except fleet.FleetPayloadError as exc:
            return f"stop: {name}'s answer is not one this console reads ({exc})"
        except Exception as exc:
            return f"not stopped: {str(exc).splitlines()[0][:120]}"
        if self.mono() - asked < fleet.STOP_TIMEOUT_S * 0.8:
            current = self.row(name)
            if current is None or current.state == "lost":
                return f"not stopped: {name} is not there to take a stop"
            return (
                f"not stopped: this console may not stop {name} (the router let the stop through to "
                f"nobody: its access control on {fleet.key(name, fleet.STOP)})"
            )
        return f"not stopped: {name} did not answer within {fleet.STOP_TIMEOUT_S:g} s"
