"""Pacing a slow client's big frames below the rate it reads at.

A client that reads slower than a camera publishes keeps every buffer between us full: our kernel's
unsent bytes, the network, its own receive buffer (often 256 KiB). A small message then waits behind
all of it, however the server orders its queues: 256 KiB at 6 MB/s is 42 ms before anything else we
do. Sending the big frames a little slower than the client reads keeps those buffers nearly empty, so
a small message waits only for the one frame (or fragment) on the wire; the big topic loses a few
more old frames (queue_length 1 keeps the latest), which a client that slow was losing anyway.

How fast a client reads is measured while it lags: a big write that had to wait for the socket to
drain returned with the buffers full, and between two such moments the bytes written are the bytes
the client read (aiohttp waits for the drain only once its own limit is passed, every few 64 KiB
writes, so the writes in between count too). Bytes over time, over at least ``SAMPLE_S``, is a
sample; a sample is at most the client's rate (less when the buffers ran empty in between, which is
what pacing is for), so the estimate is the largest sample of the last ``WINDOW_S``, as BBR filters
its delivery rate.

Only a client that cannot keep up is paced: one whose estimate is below ``LAG`` of the bytes/s its
big topics bring (``offered``, over ``OFFER_S``); a client that lags for a moment (a busy machine)
keeps every frame. A paced client's big frames start no sooner than ``size / (SHARE * rate)`` after
the previous one started. Every ``PROBE_AFTER_S`` without a sample that matches the estimate (a
client paced below its rate gives none, or only smaller ones), the pace grows by ``PROBE``, until
the buffers fill again and a sample says what the client takes now.

A frame a paced client takes longer than ``WAIT_S`` to read (a camera frame as JSON, without
``fragment_size``, to a client reading a few MB/s) holds every message behind it that long; no order
of queues helps once its bytes are on the wire, as a WebSocket message cannot be interleaved. Such
frames are spaced so that a small message waits longer than ``WAIT_S`` at most ``OVER_WAIT_SHARE``
of the time (each delays the messages that come during its first ``size / rate - WAIT_S``): the
small topic's p95 stays within ``WAIT_S`` however few frames that client then gets. A client that
asks for ``fragment_size`` gets every frame it can read, as fragments are small. A frame that comes
alone (after a pause longer than ``SAMPLE_S``) starts a new measurement; if its write waited for the
drain, its size less ``BUFFERED`` (what may still sit in the buffers when it returns) over that wait
is a sample, so that spaced frames keep the estimate up to date.

Pure: loop times in, decisions out; no I/O.
"""

from __future__ import annotations

from collections import deque

PACED_BYTES = 16 * 1024  # frames this big or bigger are paced; smaller ones (status, odometry) never
BLOCKED_S = 0.002  # a write that took this long waited for the socket to drain
WINDOW_S = 5.0  # the estimate: the largest sample this recent
CONFIRM = 0.95  # a sample this close to the estimate confirms it
LAG = 0.9  # paced only while the estimate is below this share of what its big topics bring
OFFER_S = 1.0  # the window of that offered rate
SAMPLE_S = 0.25  # backlogged time that makes one estimate of the read rate
SHARE = 0.8  # big frames use at most this share of the measured read rate
PROBE_AFTER_S = 2.0
PROBE = 1.25
WAIT_S = 0.05  # how long a paced client's big frame may hold the messages behind it (--paced-wait-ms) ...
OVER_WAIT_SHARE = 0.025  # ... except this share of the time
# still buffered when a write returns: the transport's low-water mark (16 KiB), the kernel's unsent
# bytes (bridge.wire.UNSENT_BYTES, 64 KiB) and a client's receive buffer (Linux: 256 KiB for 128 KiB asked)
BUFFERED = 384 * 1024


class Pacer:
    """One client's pacing of big frames (module doc)."""

    __slots__ = ("_best", "_bytes", "_confirmed", "_last_end", "_next_at", "_offer", "_offered", "_probe",
                 "_samples", "_since", "_wait")  # fmt: skip

    def __init__(self, wait_s: float | None = WAIT_S) -> None:
        self._wait = wait_s  # None: a big frame may hold the messages behind it as long as it takes
        self._best: float | None = None  # the largest recent sample, bytes/s; None: never lagged
        self._probe = 1.0
        self._samples: deque[tuple[float, float]] = deque()
        self._confirmed = 0.0
        self._next_at = 0.0
        self._since: float | None = None  # the last moment the buffers were full
        self._bytes = 0
        self._last_end: float | None = None  # when the last big write returned
        self._offer: tuple[float, int] | None = None  # (window start, bytes) of big frames queued
        self._offered = 0.0  # bytes/s of big frames queued for the client, over the last window

    @property
    def rate(self) -> float | None:
        """The client's measured read rate, bytes/s, probed upward; None: it never lagged."""
        return None if self._best is None else self._best * self._probe

    @property
    def paced(self) -> bool:
        return self._next_at > 0.0

    def next_at(self) -> float:
        """Time (``time.monotonic``) before which no big frame should start."""
        return self._next_at

    def offered(self, size: int, at: float) -> None:
        """A frame of ``size`` bytes was queued for the client at ``at``."""
        if size < PACED_BYTES:
            return
        if self._offer is None:
            self._offer = (at, 0)
        start, total = self._offer
        total += size
        if at - start >= OFFER_S:
            self._offered = total / (at - start)
            self._offer = (at, 0)
        else:
            self._offer = (start, total)

    def wrote(self, size: int, started: float, ended: float) -> None:
        """A frame of ``size`` bytes was handed to the socket from ``started`` to ``ended``."""
        if size < PACED_BYTES:
            return
        alone = self._last_end is None or started - self._last_end > SAMPLE_S
        self._last_end = ended
        if alone:  # the buffers had time to run empty: nothing before counts
            self._since = None
        if ended - started >= BLOCKED_S:  # the buffers were full when this write returned
            if alone and self._best is not None and size > 2 * BUFFERED:
                self._sampled(ended, (size - BUFFERED) / (ended - started))
            if self._since is not None:
                self._bytes += size
                if ended - self._since >= SAMPLE_S:
                    self._sampled(ended, self._bytes / (ended - self._since))
            if self._since is None or ended - self._since >= SAMPLE_S:
                self._since, self._bytes = ended, 0
        elif self._since is not None:
            self._bytes += size
        if self._best is None:
            return
        if ended - self._confirmed >= PROBE_AFTER_S:
            self._probe *= PROBE
            self._confirmed = ended
        rate = self._best * self._probe
        if rate >= LAG * self._offered:
            self._next_at = 0.0
            return
        self._next_at = started + size / (SHARE * rate)
        hold = size / rate  # what a message behind this frame waits
        if self._wait is not None and hold > self._wait:
            self._next_at = max(self._next_at, started + (hold - self._wait) / OVER_WAIT_SHARE)

    def _sampled(self, at: float, sample: float) -> None:
        self._samples.append((at, sample))
        while self._samples[0][0] < at - WINDOW_S:
            self._samples.popleft()
        self._best = max(s for _t, s in self._samples)
        if sample >= CONFIRM * self._best:
            self._probe = 1.0
            self._confirmed = at
