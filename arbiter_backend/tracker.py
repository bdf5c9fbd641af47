"""The latency tracker (the seed's ``latency_tracker.py``), independent of transport.

A transport hands it the text of each ``/stamped_cmd_vel`` message with the
wall-clock receive time; it answers with the record to publish on
``/latency_report`` and the clamped twist to forward on ``/cmd_vel_measured``.
Malformed envelopes are counted and their last error kept; they are never
raised and never forwarded. The watchdog asks for one zero twist when commands
stop arriving.

Safety rules, applied to what is forwarded (the record keeps what was asked):

* a command older than ``max_command_age_ms`` on arrival (judged with the sender's
  clock-offset estimate when the envelope carries one) is *stale*: recorded and
  reported (it is a latency measurement, and its report lets the sender estimate
  its clock offset), counted, never forwarded; if the robot was moving it gets one
  zero instead;
* velocities are clamped to the limits, and speeding up is limited to the
  acceleration limits (slowing down never is).
"""

from __future__ import annotations

import itertools
import json
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from arbiter_core import envelope
from arbiter_core.kinematics import DEFAULT_LIMITS, Limits, clamp_twist, limit_speedup
from arbiter_core.record import LatencyRecord, build_record, command_age_ms, latency_ms, latency_stats

NODE_NAME = "latency_tracker"
DEFAULT_LIMIT = 100
DEFAULT_MAX_COMMAND_AGE_MS = 300.0
MAX_ACCEL_DT_S = 0.1  # a speed-up step never assumes more than one 10 Hz period has passed


@dataclass(frozen=True)
class Accepted:
    record: LatencyRecord
    forward: tuple[float, float] | None  # the twist to publish on /cmd_vel_measured; None: nothing
    text: str  # the record as JSON: the /latency_report payload, serialised once

    @property
    def stale(self) -> bool:
        return self.record.stale


class LatencyTracker:
    """The seed's latency tracker without its transport: takes ``/stamped_cmd_vel`` payloads, keeps
    the last ``max_records`` records (pre-serialised) and their latencies for the stats, decides what
    is forwarded on ``/cmd_vel_measured`` (safety rules above), and answers the HTTP API's queries.

    Thread-safe: a transport's thread calls :meth:`on_stamped` and :meth:`watchdog_due` while the API
    reads under the same lock.
    """

    def __init__(
        self,
        deploy_mode: str = "native",
        max_records: int = 10_000,
        cmd_timeout: float = 0.5,
        limits: Limits = DEFAULT_LIMITS,
        max_command_age_ms: float = DEFAULT_MAX_COMMAND_AGE_MS,
        clock_ns: Callable[[], int] = time.time_ns,
        monotonic: Callable[[], float] = time.monotonic,
    ) -> None:
        if max_records < 1:
            raise ValueError("max_records must be at least 1")
        if not max_command_age_ms >= 0:
            raise ValueError("max_command_age_ms must be 0 (off) or positive")
        self.deploy_mode = deploy_mode
        self.max_records = max_records
        self.cmd_timeout = cmd_timeout
        self.limits = limits
        self.max_command_age_ms = max_command_age_ms
        self._clock_ns = clock_ns
        self._monotonic = monotonic
        self._lock = threading.Lock()
        self._texts: deque[str] = deque(maxlen=max_records)  # each record's JSON: kept serialised for the API
        self._latencies = np.zeros(max_records, dtype=np.float64)
        self._lat_next = 0
        self.total_seen = 0  # also the rx_seq of the newest record
        self.negative = 0
        self.rejected = 0
        self.stale = 0
        self.last_error: str | None = None
        self.last_stale_age_ms: float | None = None
        self._started = monotonic()
        self._last_cmd: float | None = None
        self._stopped_sent = True  # nothing to stop before the first command
        self._fwd = (0.0, 0.0)  # the last twist forwarded
        self._fwd_at: float | None = None

    # -- input ------------------------------------------------------------------------
    def on_stamped(self, text: Any, recv_ns: int | None = None) -> Accepted | None:
        """Handle one ``/stamped_cmd_vel`` payload; None when it was rejected (and counted)."""
        if recv_ns is None:
            recv_ns = self._clock_ns()
        try:
            if not isinstance(text, (str, bytes)):
                raise envelope.EnvelopeError("bad_type", f"data must be a string, got {type(text).__name__}")
            cmd = envelope.parse(text)
        except envelope.EnvelopeError as exc:
            with self._lock:
                self.rejected += 1
                self.last_error = f"{exc.kind}: {exc}"
            return None
        latency = latency_ms(cmd, recv_ns)
        age = command_age_ms(cmd, latency)
        stale = 0 < self.max_command_age_ms < age
        now = self._monotonic()
        with self._lock:
            self.total_seen += 1
            sent_ns = self._clock_ns()  # NTP t2: the report leaves now (the tracker's own time excluded)
            record = build_record(
                cmd, recv_ns, self.deploy_mode, stale=stale, rx_seq=self.total_seen, sent_ns=sent_ns
            )
            if latency < 0:
                self.negative += 1  # kept as measured: a clock offset, never clipped
            text = record.to_json()
            self._texts.append(text)
            self._latencies[self._lat_next] = latency
            self._lat_next = (self._lat_next + 1) % self.max_records
            if stale:
                self.stale += 1
                self.last_stale_age_ms = round(age, 3)
                forward = self._stop_if_moving(now)
            else:
                forward = self._next_twist(cmd.linear_x, cmd.angular_z, now)
                self._last_cmd = now
                self._stopped_sent = False
        return Accepted(record, forward, text)

    def _next_twist(self, v: float, w: float, now: float) -> tuple[float, float]:
        """Clamp to the limits, then rate-limit speeding up (lock held)."""
        v, w = clamp_twist(v, w, self.limits)
        dt = MAX_ACCEL_DT_S if self._fwd_at is None else min(max(now - self._fwd_at, 0.0), MAX_ACCEL_DT_S)
        pv, pw = self._fwd
        out = (
            limit_speedup(pv, v, self.limits.max_linear_accel, dt),
            limit_speedup(pw, w, self.limits.max_angular_accel, dt),
        )
        self._fwd, self._fwd_at = out, now
        return out

    def _stop_if_moving(self, now: float) -> tuple[float, float] | None:
        if self._fwd == (0.0, 0.0):
            return None
        self._fwd, self._fwd_at = (0.0, 0.0), now
        return (0.0, 0.0)

    def watchdog_due(self) -> bool:
        """True exactly once after ``cmd_timeout`` without a valid command (send one zero twist)."""
        with self._lock:
            if self._stopped_sent or self._last_cmd is None:
                return False
            now = self._monotonic()
            if now - self._last_cmd < self.cmd_timeout:
                return False
            self._stopped_sent = True
            self._fwd, self._fwd_at = (0.0, 0.0), now
            return True

    # -- API ----------------------------------------------------------------------------
    def _snapshot(self, limit: int, since: int | None) -> tuple[dict[str, Any], list[str]]:
        """Everything but the records, and the records' JSON texts to include."""
        with self._lock:
            n = len(self._texts)
            window = self._latencies[:n] if n < self.max_records else self._latencies
            stats = latency_stats(window)
            total = self.total_seen
            first = total - n + 1  # rx_seq of the oldest record kept
            more = False
            if limit <= 0:
                start = stop = n
            elif since is None:
                start, stop = max(0, n - limit), n
            else:
                start = min(max(since + 1, first), total + 1) - first
                stop = min(start + limit, n)
                more = stop < n
            rejected, last_error, negative, stale = self.rejected, self.last_error, self.negative, self.stale
            texts = list(itertools.islice(self._texts, start, stop))
        body: dict[str, Any] = {
            "stats": stats,
            "deploy_mode": self.deploy_mode,
            "total_seen": total,
            "window": n,
            "dropped": total - n,
            "rejected": rejected,
            "last_error": last_error,
            "negative": negative,
            "stale": stale,
            "max_command_age_ms": self.max_command_age_ms,
            "last_rx_seq": total,
        }
        if since is not None:
            body["more"] = more
        return body, texts

    def latency_response(self, limit: int = DEFAULT_LIMIT, since: int | None = None) -> dict[str, Any]:
        """The seed's ``GET /api/latency`` body, plus totals; stats cover the whole window.

        Without ``since``: the ``limit`` most recent records. With ``since``: the records whose
        ``rx_seq`` (the tracker's receive counter, 1-based, across all senders) is greater, oldest
        first, at most ``limit``; ``more`` says whether others follow. A client passes the
        ``last_rx_seq`` it has seen and gets only what is new.
        """
        response: dict[str, Any] = json.loads(self.latency_response_text(limit, since))
        return response

    def latency_response_text(self, limit: int = DEFAULT_LIMIT, since: int | None = None) -> str:
        """``latency_response`` as JSON text; records are spliced in pre-serialised (the API's path)."""
        body, texts = self._snapshot(limit, since)
        head = json.dumps(body, allow_nan=False, separators=(",", ":"))
        return '{"records":[' + ",".join(texts) + "]," + head[1:]

    def window_latencies(self) -> np.ndarray:
        """A copy of the latencies the stats cover (the fleet's p50 and p95; not in arrival order)."""
        with self._lock:
            n = len(self._texts)
            return (self._latencies[:n] if n < self.max_records else self._latencies).copy()

    def health(self) -> dict[str, Any]:
        now = self._monotonic()
        with self._lock:
            since = None if self._last_cmd is None else round(now - self._last_cmd, 3)
            return {
                "status": "ok",
                "node": NODE_NAME,
                "uptime_s": round(now - self._started, 3),
                "records_count": len(self._texts),
                "total_seen": self.total_seen,
                "rejected": self.rejected,
                "negative": self.negative,
                "stale": self.stale,
                "last_stale_age_ms": self.last_stale_age_ms,
                "max_command_age_ms": self.max_command_age_ms,
                "last_error": self.last_error,
                "seconds_since_last_command": since,
                "deploy_mode": self.deploy_mode,
            }
