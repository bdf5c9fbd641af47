"""Round trip, clock offset and loss for stamped commands, measured by the sender (pure, thread-safe).

For each command the sender notes its wall stamp ``t0`` (the envelope's, ms) and
a monotonic send time. The tracker's ``/latency_report`` for it carries the raw
one-way figure ``raw = t1 - t0`` (tracker receive wall time minus the stamp: the
seed's number, which includes the clock offset). When the report arrives at
monotonic time ``m3``:

* round trip ``rtt = m3 - m0`` (monotonic, immune to wall-clock steps);
* the NTP estimate, with ``t3 = t0 + rtt`` and the tracker replying at once
  (``t2 = t1``): ``offset = ((t1 - t0) + (t2 - t3)) / 2 = raw - rtt / 2``, the
  tracker's clock minus ours, with error at most ``rtt / 2`` (the path asymmetry
  bound);
* the offset in use is the sample with the lowest RTT over the last
  ``offset_window_s`` seconds (NTP's clock filter: the least queueing, so the
  tightest bound), and ``corrected one-way = raw - offset``. The window is one of
  time, not of count: a flood of commands whose reports queue behind each other
  (huge RTTs, offsets off by half of them) cannot push the good samples out;
* an offset is only *significant* when it exceeds a threshold by more than its
  own error bound (``significant``): a clock alarm needs a sure offset.

Negative raw latencies are kept and counted, never clipped. A command with no
report after ``lost_after_s`` counts as lost, timestamped, so loss is reported
per window and a disconnect shows as a gap; a report that arrives later after
all (queued, not lost on the link) takes the command back out of the lost count
and counts it as ``late``.
"""

from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass, replace

from arbiter_core import stats
from arbiter_core.record import LatencyRecord

MATCH_TOLERANCE_MS = 0.05  # a report matches a send when t1 - raw gives back t0 (µs stamps, float s)


@dataclass(frozen=True)
class OffsetEstimate:
    offset_ms: float  # tracker clock minus ours
    uncertainty_ms: float  # rtt / 2 of the sample used
    rtt_ms: float
    samples: int  # candidates in the filter's window

    def significant(self, threshold_ms: float) -> bool:
        """The offset surely exceeds ``threshold_ms``: even at the edge of its error bound."""
        return abs(self.offset_ms) - self.uncertainty_ms > threshold_ms


@dataclass(frozen=True)
class MeterSummary:
    """This console's own view of the link: round trip, one-way (raw and offset-corrected), the clock
    offset in use, and what became of the commands sent."""

    n: int = 0  # matched round trips in the sample window
    raw_p50_ms: float | None = None
    raw_p95_ms: float | None = None
    corrected_p50_ms: float | None = None
    corrected_p95_ms: float | None = None
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
    corrected_ms: float


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
        self._pending: dict[int, tuple[float, float]] = {}  # seq -> (send monotonic s, stamp ms)
        # sliding-window minimum of RTT: (arrival monotonic, offset, rtt), RTTs increasing left to right,
        # so the left end is the lowest-RTT sample of the last offset_window_s (O(1) amortised per report)
        self._offsets: deque[tuple[float, float, float]] = deque()
        self._candidates = 0
        self.offset_window_s = offset_window_s
        self._expired: dict[int, tuple[float, float]] = {}  # counted lost; a late report may still come
        self.max_expired = max_expired
        self._samples: deque[Sample] = deque(maxlen=history)
        self._lost_at: deque[float] = deque()
        self.lost_after_s = lost_after_s
        self.loss_window_s = loss_window_s
        self.max_pending = max_pending
        self.sent = 0
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
            self._filter(arrival_mono, raw - rtt / 2.0, rtt)
            sample = Sample(seq, raw, rtt, raw - self._offsets[0][1])
            self._samples.append(sample)
            self.matched += 1
            if raw < 0:
                self.negative += 1
            return sample

    def _filter(self, now: float, offset: float, rtt: float) -> None:
        """Add a candidate to the sliding-window minimum of RTT (under the lock)."""
        window = self._offsets
        while window and window[-1][2] >= rtt:
            window.pop()
        window.append((now, offset, rtt))
        while window[0][0] < now - self.offset_window_s:
            window.popleft()
        self._candidates += 1

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
    def offset(self) -> OffsetEstimate | None:
        with self._lock:
            if not self._offsets:
                return None
            _at, off, rtt = self._offsets[0]
            return OffsetEstimate(off, rtt / 2.0, rtt, len(self._offsets))

    def samples(self) -> list[Sample]:
        with self._lock:
            return list(self._samples)

    def lost_in_window(self) -> int:
        with self._lock:
            return len(self._lost_at)

    def summary(self) -> MeterSummary:
        """Figures for display and benchmarks (ms, rounded to 4 places; percentiles by the seed's rule)."""
        samples = self.samples()
        est = self.offset()
        raw = [s.raw_ms for s in samples]
        rtt = [s.rtt_ms for s in samples]
        cor = [s.corrected_ms for s in samples]

        def pct(values: list[float], q: float) -> float | None:
            return round(stats.percentile(values, q), 4) if values else None

        return MeterSummary(
            n=len(samples),
            raw_p50_ms=pct(raw, 0.5),
            raw_p95_ms=pct(raw, 0.95),
            corrected_p50_ms=pct(cor, 0.5),
            corrected_p95_ms=pct(cor, 0.95),
            rtt_p50_ms=pct(rtt, 0.5),
            rtt_p95_ms=pct(rtt, 0.95),
            offset=None
            if est is None
            else OffsetEstimate(
                round(est.offset_ms, 4), round(est.uncertainty_ms, 4), round(est.rtt_ms, 4), est.samples
            ),
            sent=self.sent,
            matched=self.matched,
            negative=self.negative,
            lost=self.lost,
            late=self.late,
            lost_in_window=self.lost_in_window(),
            in_flight=len(self._pending),
        )
