"""Round trip, clock offset and loss for stamped commands, measured by the sender (pure, thread-safe).

For each command the sender notes its wall stamp ``t0`` (the envelope's, ms) and
a monotonic send time. The tracker's ``/latency_report`` for it carries the raw
one-way figure ``raw = t1 - t0`` (tracker receive wall time minus the stamp: the
seed's number, which includes the clock offset) and, from our tracker, ``t1`` and
``t2`` (``t_recv_ms``, ``t_sent_ms``: when it received the command and when it
sent the report). When the report arrives at monotonic time ``m3``:

* round trip ``rtt = m3 - m0`` (monotonic, immune to wall-clock steps);
* the NTP exchange, with ``t3 = t0 + rtt``: ``delay = rtt - (t2 - t1)`` (the time
  the tracker held the command taken out) and ``offset = ((t1 - t0) + (t2 - t3)) / 2``,
  the tracker's clock minus ours, whose error is at most ``delay / 2`` whatever the
  path asymmetry. A seed tracker's record has no ``t2``: then ``t2 = t1``;
* the exchanges feed a clock *model* (:mod:`arbiter_core.clockmodel`: offset and
  drift from a line through the least-delay exchange of each time bucket, clock
  steps detected and re-anchored), and ``corrected one-way = raw - offset(t)``;
* every corrected figure comes with its interval: the one-way delay lies in
  ``[raw - offset - bound, raw - offset + bound]`` (the offset's bound) and, as no
  direction takes less than nothing or more than the whole delay, in ``[0, delay]``;
  when both hosts say their clocks are synchronised (``host_error_ms``: the sum of
  their estimated errors) it lies in ``raw ± host_error_ms`` too. The p50 and p95
  of the truth lie between the p50 (p95) of the lower ends and of the upper ends;
* jitter is the standard deviation of the drift-corrected one-way figures (raw
  figures also move with the drift, which is not jitter);
* an offset is only *significant* when it exceeds a threshold by more than its
  own error bound (``significant``): a clock alarm needs a sure offset.

Negative raw latencies are kept and counted, never clipped. A command with no
report after ``lost_after_s`` counts as lost, timestamped, so loss is reported
per window and a disconnect shows as a gap; a report that arrives later after
all (queued, not lost on the link) takes the command back out of the lost count
and counts it as ``late``.
"""

from __future__ import annotations

import math
import threading
from collections import deque
from dataclasses import dataclass, replace
from typing import overload

import numpy as np

from arbiter_core import stats
from arbiter_core.clockmodel import ClockEstimate, ClockModel, ntp_exchange
from arbiter_core.record import LatencyRecord

MATCH_TOLERANCE_MS = 0.05  # a report matches a send when t1 - raw gives back t0 (µs stamps, float s)


@dataclass(frozen=True)
class OffsetEstimate:
    offset_ms: float  # tracker clock minus ours
    uncertainty_ms: float  # the truth lies within offset_ms ± this (the clock model's bound)
    rtt_ms: float  # the least delay among the exchanges the model uses
    samples: int  # bucket minima in the model
    drift_ppm: float | None = None  # None: too short a span yet
    drift_bound_ppm: float | None = None
    steps: int = 0  # clock steps detected (the model re-anchored)

    def significant(self, threshold_ms: float) -> bool:
        """The offset surely exceeds ``threshold_ms``: even at the edge of its error bound."""
        return abs(self.offset_ms) - self.uncertainty_ms > threshold_ms

    def seconds_until(self, threshold_ms: float) -> float | None:
        """When the drift will take |offset| past ``threshold_ms`` (s from now); None: it will not."""
        return _as_clock(self).seconds_until(threshold_ms)


def _as_clock(e: OffsetEstimate) -> ClockEstimate:
    return ClockEstimate(0.0, e.offset_ms, e.uncertainty_ms, e.drift_ppm, e.drift_bound_ppm, e.rtt_ms,
                         e.samples, e.steps)  # fmt: skip


@overload
def _rounded(v: float, digits: int | None) -> float: ...
@overload
def _rounded(v: None, digits: int | None) -> None: ...
def _rounded(v: float | None, digits: int | None) -> float | None:
    return v if v is None or digits is None else round(v, digits)


def _estimate(c: ClockEstimate, steps: int, digits: int | None = None) -> OffsetEstimate:
    return OffsetEstimate(_rounded(c.offset_ms, digits), _rounded(c.bound_ms, digits),
                          _rounded(c.best_delay_ms, digits), c.points, _rounded(c.drift_ppm, digits),
                          _rounded(c.drift_bound_ppm, digits), steps)  # fmt: skip


@dataclass(frozen=True)
class MeterSummary:
    """This console's own view of the link: round trip, one-way (raw and offset-corrected), the clock
    offset in use, and what became of the commands sent."""

    n: int = 0  # matched round trips in the sample window
    raw_p50_ms: float | None = None
    raw_p95_ms: float | None = None
    corrected_p50_ms: float | None = None
    corrected_p95_ms: float | None = None
    # where the truth lies: [lo, hi] of each corrected figure (module docstring)
    corrected_p50_lo_ms: float | None = None
    corrected_p50_hi_ms: float | None = None
    corrected_p95_lo_ms: float | None = None
    corrected_p95_hi_ms: float | None = None
    jitter_ms: float | None = None  # stddev of the drift-corrected one-way figures
    host_bound_used: bool = False  # the hosts' own sync error made the interval tighter
    rtt_p50_ms: float | None = None
    rtt_p95_ms: float | None = None
    offset: OffsetEstimate | None = None
    sent: int = 0
    matched: int = 0
    negative: int = 0
    lost: int = 0
    late: int = 0
    lost_in_window: int = 0
    in_flight: int = 0

    def shown(self) -> MeterSummary:
        """Without what changes with every command and is never shown (commands in flight): equal
        summaries then mean an unchanged screen."""
        return replace(self, in_flight=0)


@dataclass(frozen=True)
class Sample:
    seq: int
    raw_ms: float
    rtt_ms: float
    corrected_ms: float  # with the model at its arrival (live)
    delay_ms: float = math.nan  # rtt minus the tracker's holding time
    at_s: float = math.nan  # monotonic midpoint of the exchange
    epoch: int = 0  # the clock model's epoch at arrival (a step starts a new one)
    bound_ms: float = math.nan  # the offset's bound at arrival


class LatencyMeter:
    def __init__(
        self,
        offset_window_s: float = 64.0,
        history: int = 2000,
        lost_after_s: float = 2.0,
        loss_window_s: float = 10.0,
        max_pending: int = 100_000,
        max_expired: int = 10_000,
    ) -> None:
        self._lock = threading.Lock()
        self._written = threading.Condition(self._lock)  # a command was written (``on_send``)
        self._pending: dict[int, tuple[float, float]] = {}  # seq -> (send monotonic s, stamp ms)
        self.clock = ClockModel(window_s=max(offset_window_s, 2.0))
        self._last_at: float | None = None
        self.offset_window_s = offset_window_s
        self._expired: dict[int, tuple[float, float]] = {}  # counted lost; a late report may still come
        self.max_expired = max_expired
        self._samples: deque[Sample] = deque(maxlen=history)
        self._lost_at: deque[float] = deque()
        self.lost_after_s = lost_after_s
        self.loss_window_s = loss_window_s
        self.max_pending = max_pending
        self.sent = 0
        self.last_send_mono: float | None = None  # when the newest command was written to the socket
        self.matched = 0
        self.negative = 0
        self.lost = 0
        self.late = 0  # reported after lost_after_s: queued somewhere, not lost on the link
        self.foreign = 0  # reports of commands not ours (another console)

    # -- events ---------------------------------------------------------------------------------
    def on_send(self, seq: int, stamp_ms: float, send_mono: float) -> None:
        with self._lock:
            if len(self._pending) >= self.max_pending:  # a stuck link: the oldest count as lost
                oldest = next(iter(self._pending))
                del self._pending[oldest]
                self._count_lost(send_mono)
            self._pending[seq] = (send_mono, stamp_ms)
            self.sent += 1
            self.last_send_mono = send_mono
            self._written.notify_all()

    def wait_sent(self, count: int, timeout_s: float) -> bool:
        """Wait (at most ``timeout_s``) until more than ``count`` commands were written; True if so."""
        with self._written:
            return self._written.wait_for(lambda: self.sent > count, timeout_s)

    def on_report(self, record: LatencyRecord, arrival_mono: float) -> Sample | None:
        """Match a tracker record to our send; None when it is not one of ours (or has no ``seq``,
        as a seed tracker's records do not)."""
        seq, raw, t1_ms = record.seq, record.latency_ms, record.timestamp * 1000.0
        if seq is None:
            return None
        with self._lock:
            sent = self._pending.get(seq)
            late = sent is None and seq in self._expired
            if late:
                sent = self._expired[seq]
            if sent is None or abs((t1_ms - raw) - sent[1]) > MATCH_TOLERANCE_MS:
                self.foreign += 1
                return None
            if late:
                del self._expired[seq]
                self.late += 1
                self.lost -= 1
                if self._lost_at:
                    self._lost_at.popleft()
            else:
                del self._pending[seq]
            send_mono, _ = sent
            rtt = (arrival_mono - send_mono) * 1000.0
            held = 0.0  # a seed tracker's record: as if it replied at once (t2 = t1)
            if record.t_sent_ms is not None and record.t_recv_ms is not None:
                held = record.t_sent_ms - record.t_recv_ms
            ex = ntp_exchange(raw, held, rtt, send_mono)  # raw = t1 - t0, the tracker's own figure
            self.clock.add(ex)
            est = self.clock.estimate(ex.at_s)
            assert est is not None  # an exchange was just added (or held back with a model in place)
            self._last_at = ex.at_s if self._last_at is None else max(self._last_at, ex.at_s)
            sample = Sample(seq, raw, rtt, raw - est.offset_ms, ex.delay_ms, ex.at_s, est.epoch, est.bound_ms)
            self._samples.append(sample)
            self.matched += 1
            if raw < 0:
                self.negative += 1
            return sample

    def expire(self, now_mono: float) -> int:
        """Count commands unreported for ``lost_after_s`` as lost; returns how many were just counted."""
        n = 0
        with self._lock:
            cutoff = now_mono - self.lost_after_s
            for seq, (sent, stamp) in list(self._pending.items()):
                if sent >= cutoff:
                    break  # insertion order is send order
                del self._pending[seq]
                self._expired[seq] = (sent, stamp)
                self._count_lost(now_mono)
                n += 1
            while len(self._expired) > self.max_expired:
                del self._expired[next(iter(self._expired))]
            while self._lost_at and self._lost_at[0] < now_mono - self.loss_window_s:
                self._lost_at.popleft()
        return n

    def _count_lost(self, now_mono: float) -> None:
        self.lost += 1
        self._lost_at.append(now_mono)

    def reset_pending(self, now_mono: float) -> None:
        """The link dropped: what is in flight will never be reported; count it now."""
        with self._lock:
            for _ in range(len(self._pending)):
                self._count_lost(now_mono)
            self._pending.clear()

    # -- reading --------------------------------------------------------------------------------
    def offset(self, at_mono: float | None = None) -> OffsetEstimate | None:
        """The clock model at monotonic time ``at_mono`` (default: the newest exchange's)."""
        with self._lock:
            return self._offset(at_mono)

    def _offset(self, at_mono: float | None, digits: int | None = None) -> OffsetEstimate | None:
        at = self._last_at if at_mono is None else at_mono
        if at is None:
            return None
        est = self.clock.estimate(at)
        return None if est is None else _estimate(est, self.clock.epoch, digits)

    def samples(self) -> list[Sample]:
        with self._lock:
            return list(self._samples)

    def lost_in_window(self) -> int:
        with self._lock:
            return len(self._lost_at)

    def summary(self, host_error_ms: float | None = None, at_mono: float | None = None) -> MeterSummary:
        """Figures for display and benchmarks (ms, rounded to 4 places; percentiles by the seed's rule).

        The samples since the clock model's last re-anchoring are corrected with the model as it is now
        (hindsight: the drift it has learnt applies to them too); older ones keep their correction at
        arrival. ``host_error_ms``: both hosts say they are synchronised, to within this much together.
        """
        with self._lock:
            samples = list(self._samples)
            est = self._offset(at_mono, 4)
            epoch, anchor = self.clock.epoch, self.clock.anchor_s
            pick = np.array([s.epoch == epoch or s.at_s >= anchor for s in samples], dtype=bool)
            now = [s.at_s for s, p in zip(samples, pick, strict=True) if p]
            fitted = self.clock.offsets_and_bounds(now) if now else None
            in_flight = len(self._pending)
        raw = np.array([s.raw_ms for s in samples], dtype=np.float64)
        rtt = [s.rtt_ms for s in samples]
        offsets = np.array([s.raw_ms - s.corrected_ms for s in samples], dtype=np.float64)
        bounds = np.array([s.bound_ms for s in samples], dtype=np.float64)
        delay = np.array([s.delay_ms for s in samples], dtype=np.float64)
        if fitted is not None:
            offsets[pick], bounds[pick] = fitted
        cor = raw - offsets
        lo = np.maximum(cor - bounds, 0.0)
        hi = np.minimum(cor + bounds, np.where(np.isnan(delay), np.inf, delay))
        used_host = False
        if host_error_ms is not None and len(samples):
            h_lo, h_hi = np.maximum(raw - host_error_ms, lo), np.minimum(raw + host_error_ms, hi)
            used_host = bool(np.any(h_lo > lo) or np.any(h_hi < hi))
            lo, hi = h_lo, h_hi

        def pct(values: list[float] | np.ndarray, q: float) -> float | None:
            return round(stats.percentile(values, q), 4) if len(values) else None

        return MeterSummary(
            n=len(samples),
            raw_p50_ms=pct(raw, 0.5),
            raw_p95_ms=pct(raw, 0.95),
            corrected_p50_ms=pct(cor, 0.5),
            corrected_p95_ms=pct(cor, 0.95),
            corrected_p50_lo_ms=pct(lo, 0.5),
            corrected_p50_hi_ms=pct(hi, 0.5),
            corrected_p95_lo_ms=pct(lo, 0.95),
            corrected_p95_hi_ms=pct(hi, 0.95),
            jitter_ms=round(float(np.std(cor)), 4) if len(samples) > 1 else None,
            host_bound_used=used_host,
            rtt_p50_ms=pct(rtt, 0.5),
            rtt_p95_ms=pct(rtt, 0.95),
            offset=est,
            sent=self.sent,
            matched=self.matched,
            negative=self.negative,
            lost=self.lost,
            late=self.late,
            lost_in_window=self.lost_in_window(),
            in_flight=in_flight,
        )
