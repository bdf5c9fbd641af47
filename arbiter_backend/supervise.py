"""Every long-lived worker of the backend under one supervisor, whichever the transport.

A worker is a loop that runs until the backend stops it: a thread (``Supervisor.thread``: the topic
monitor on DDS, the rclpy executors) or an asyncio task (``Supervisor.task``: the embedded transport's
watchdog, simulator and topic monitor, the relay's QoS follower, the fleet announcer). When its body
raises, the supervisor logs the error once (a traceback the first time an error is seen, nothing more
while the same error repeats), waits (from ``MIN_BACKOFF_S``, doubling, at most ``MAX_BACKOFF_S``; back
to the minimum after a run of ``STABLE_S``) and runs it again. After ``GIVE_UP_AFTER`` failures in a
row, none of them after a stable run, a worker that may give up is ``failed`` and left stopped (a body
that fails that fast fails for a reason a restart does not mend), loudly: a critical log line, and
``/api/health`` says ``"status": "degraded"`` and names it in ``failed_workers``. The workers on the
command path (``give_up=False``: the rclpy executor that spins the tracker, the embedded watchdog) never
give up: they restart every ``MAX_BACKOFF_S`` for as long as they fail. A body that raises what is not an
``Exception`` (``SystemExit``, ``KeyboardInterrupt``) ends the worker ``failed`` with that error, never
leaves it ``running``.

Each worker calls :meth:`Supervisor.beat` once a round: the first beat of a run says it is running again
(its listeners are told: the topic monitor's answers say "monitor restarted: …" until then), and it is
where a failure is injected for tests and drills: ``ARBITER_FAULT=NAME[@SECONDS][*TIMES][,NAME...]``
makes worker ``NAME`` raise :class:`InjectedFault` at its first beat ``SECONDS`` (default 0) after it
first started, and at the first beat of each run after that until it has failed ``TIMES`` (default 1)
times in a row (``*4`` holds it down through three backoffs). ``GET /api/health`` lists each worker
(:meth:`Supervisor.workers`): its name, state (``starting``, ``running``, ``restarting``, ``failed``,
``stopped``), restarts, last error and since when (Unix time) it is in that state.
:class:`WorkerRecord` is the bookkeeping, pure; the rest runs the loops.
"""

from __future__ import annotations

import asyncio
import logging
import os
import threading
import time
from collections.abc import Callable, Coroutine, Mapping
from dataclasses import dataclass, field
from typing import Any

log = logging.getLogger(__name__)

FAULT_ENV = "ARBITER_FAULT"
MIN_BACKOFF_S = 0.2
MAX_BACKOFF_S = 30.0
STABLE_S = 30.0  # a run this long was healthy: the next failure waits MIN_BACKOFF_S again
GIVE_UP_AFTER = 20  # failures in a row, each before a stable run: the worker is failed
STATES = ("starting", "running", "restarting", "failed", "stopped")

Listener = Callable[["WorkerRecord"], None]


class InjectedFault(RuntimeError):
    """The failure ``ARBITER_FAULT`` asks a worker for."""


@dataclass(frozen=True)
class Fault:
    """A failure asked of a worker: ``after`` seconds into its first run, ``times`` runs in a row."""

    after: float = 0.0
    times: int = 1


def parse_faults(text: str | None) -> dict[str, Fault]:
    """``"topic-monitor@2*3,fleet-announcer"`` -> ``{"topic-monitor": Fault(2.0, 3), "fleet-announcer":
    Fault()}``; ValueError naming the item that is not ``NAME[@SECONDS][*TIMES]``."""
    out: dict[str, Fault] = {}
    for item in (part.strip() for part in (text or "").split(",")):
        if not item:
            continue
        head, star, times_text = item.partition("*")
        name, at, after = head.partition("@")
        try:
            seconds = float(after) if at else 0.0
            times = int(times_text) if star else 1
        except ValueError:
            seconds, times = -1.0, 0
        if not name.strip() or not 0 <= seconds < float("inf") or not 1 <= times <= GIVE_UP_AFTER:
            raise ValueError(
                f"{FAULT_ENV}: bad item {item!r}: write NAME[@SECONDS][*TIMES] (TIMES 1 to {GIVE_UP_AFTER}), "
                "e.g. topic-monitor@2"
            )
        out[name.strip()] = Fault(seconds, times)
    return out


@dataclass
class WorkerRecord:
    """One worker's state; every method takes the times it needs (``mono``: monotonic, ``wall``: Unix)."""

    name: str
    state: str = "starting"  # until its first beat
    restarts: int = 0
    error_type: str | None = None
    error_message: str | None = None
    since: float = 0.0  # Unix time of the latest change of state
    started: float = 0.0  # monotonic time the current run began
    in_a_row: int = 0  # failures since the last stable run
    fault: Fault | None = None  # injected failures still to come
    fault_at: float | None = None  # monotonic time from which they come (set by the first ``begin``)
    give_up: bool = True  # False: restarted for as long as it fails (the command path)

    def begin(self, mono: float) -> None:
        self.started = mono
        if self.fault is not None and self.fault_at is None:
            self.fault_at = mono + self.fault.after

    def beat(self, mono: float, wall: float) -> bool:
        """A round of the worker's loop; True when this beat made it ``running`` (its first of a run).
        Raises InjectedFault when one is due."""
        if self.fault is not None and self.fault_at is not None and mono >= self.fault_at:
            left = self.fault.times - 1
            self.fault = Fault(self.fault.after, left) if left else None
            raise InjectedFault(f"{FAULT_ENV}={self.name}")
        if self.state == "running":
            return False
        self.state, self.since = "running", wall
        return True

    def fail(self, exc: BaseException, mono: float, wall: float) -> float | None:
        """The run ended with ``exc``: the seconds to wait before the next (None: give up, ``failed``)."""
        if mono - self.started >= STABLE_S:
            self.in_a_row = 0
        self.in_a_row += 1
        self.error_type, self.error_message = type(exc).__name__, str(exc)[:300]
        self.since = wall
        if self.give_up and self.in_a_row >= GIVE_UP_AFTER:
            self.state = "failed"
            return None
        self.state = "restarting"
        self.restarts += 1
        return min(MAX_BACKOFF_S, MIN_BACKOFF_S * 2.0 ** (self.in_a_row - 1))

    def die(self, exc: BaseException, wall: float) -> None:
        """The run ended with what is not an ``Exception`` (``SystemExit``...): ``failed``, not restarted."""
        self.error_type, self.error_message = type(exc).__name__, str(exc)[:300]
        self.state, self.since = "failed", wall

    def stop(self, wall: float) -> None:
        if self.state != "failed":
            self.state, self.since = "stopped", wall

    @property
    def error(self) -> str | None:
        """``Type: message`` of the last failure."""
        return None if self.error_type is None else f"{self.error_type}: {self.error_message}"

    def to_json(self) -> dict[str, Any]:
        last = None if self.error_type is None else {"type": self.error_type, "message": self.error_message}
        return {
            "name": self.name,
            "state": self.state,
            "restarts": self.restarts,
            "last_error": last,
            "since": round(self.since, 3),
        }


@dataclass
class Supervisor:
    """The backend's workers (``Servers.supervisor``): shared by both transports and the fleet."""

    faults: Mapping[str, Fault] = field(default_factory=lambda: parse_faults(os.environ.get(FAULT_ENV)))
    clock: Callable[[], float] = time.monotonic
    wall: Callable[[], float] = time.time
    _workers: dict[str, WorkerRecord] = field(default_factory=dict)
    _listeners: dict[str, list[Listener]] = field(default_factory=dict)
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def workers(self) -> list[dict[str, Any]]:
        """Each worker's state, for ``/api/health``, in the order they started."""
        with self._lock:
            return [w.to_json() for w in self._workers.values()]

    def record(self, name: str) -> WorkerRecord | None:
        return self._workers.get(name)

    def listen(self, name: str, listener: Listener) -> None:
        """``listener(record)`` on each change of ``name``'s state (on the worker's thread)."""
        self._listeners.setdefault(name, []).append(listener)

    def beat(self, name: str) -> None:
        """Called by worker ``name`` once a round (cheap: a look-up and two comparisons)."""
        w = self._workers[name]
        if w.state == "running" and w.fault is None:
            return
        with self._lock:  # a worker may beat on two threads at once (an executor's pool): one fault each
            started = w.beat(self.clock(), self.wall())
        if started:
            log.debug("%s: running", name)
            self._tell(w)

    def _register(self, name: str, give_up: bool) -> WorkerRecord:
        with self._lock:
            if name in self._workers:
                raise ValueError(f"a worker called {name} runs already")
            w = WorkerRecord(name, since=self.wall(), fault=self.faults.get(name), give_up=give_up)
            self._workers[name] = w
        return w

    def _tell(self, w: WorkerRecord) -> None:
        for listener in self._listeners.get(w.name, ()):
            try:
                listener(w)
            except Exception:
                log.exception("%s: a listener of its state failed", w.name)

    def _failed(self, w: WorkerRecord, exc: Exception) -> float | None:
        before = w.error
        with self._lock:
            delay = w.fail(exc, self.clock(), self.wall())
        if delay is None:
            log.critical(
                "%s failed %d times in a row (%s): given up, it stays stopped (GET /api/health: failed)",
                w.name, w.in_a_row, w.error, exc_info=exc,
            )  # fmt: skip
        elif w.error != before:  # a new error: its traceback, once
            log.error("%s failed, restarting in %.1f s", w.name, delay, exc_info=exc)
        else:
            log.debug("%s failed again (%s), restarting in %.1f s", w.name, w.error, delay)
        self._tell(w)
        return delay

    def _died(self, w: WorkerRecord, exc: BaseException) -> None:
        with self._lock:
            w.die(exc, self.wall())
        log.critical("%s ended by %s: not restarted (GET /api/health: failed)", w.name, w.error)
        self._tell(w)

    def _stopped(self, w: WorkerRecord) -> None:
        with self._lock:
            w.stop(self.wall())
        self._tell(w)

    # -- threads ----------------------------------------------------------------------------------
    def thread(
        self, name: str, body: Callable[[], None], stop: threading.Event, give_up: bool = True
    ) -> threading.Thread:
        """Run ``body`` on a daemon thread called ``name`` until it returns (``stop`` set: it should
        return soon after), again after each failure; ``stop`` also ends a wait between runs.
        ``give_up=False``: never given up (the command path)."""
        w = self._register(name, give_up)

        def run() -> None:
            while not stop.is_set():
                w.begin(self.clock())
                try:
                    body()
                except Exception as exc:
                    delay = self._failed(w, exc)
                    if delay is None:
                        return
                    stop.wait(delay)
                except BaseException as exc:
                    self._died(w, exc)
                    raise
                else:
                    break
            self._stopped(w)

        thread = threading.Thread(target=run, name=name, daemon=True)
        thread.start()
        return thread

    # -- asyncio tasks ----------------------------------------------------------------------------
    def task(
        self, name: str, body: Callable[[], Coroutine[Any, Any, None]], give_up: bool = True
    ) -> asyncio.Task[None]:
        """Run ``body()`` as an asyncio task until it returns or is cancelled, again after each failure.
        ``give_up=False``: never given up (the command path)."""
        w = self._register(name, give_up)

        async def run() -> None:
            try:
                while True:
                    w.begin(self.clock())
                    try:
                        await body()
                    except Exception as exc:
                        delay = self._failed(w, exc)
                        if delay is None:
                            return
                        await asyncio.sleep(delay)
                    except asyncio.CancelledError:
                        raise
                    except BaseException as exc:
                        self._died(w, exc)
                        raise
                    else:
                        break
            finally:
                self._stopped(w)

        return asyncio.get_running_loop().create_task(run(), name=name)
