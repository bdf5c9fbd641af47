"""Injected ground truth for the latency figures: the backend's wall clock shifted and drifting under
libfaketime, each direction of the link delayed by :class:`DelayProxy`, and the console's own
``RosLink`` and ``LatencyMeter`` measuring through it. Used by tests/integration/test_groundtruth.py
(one or two cases) and bench/groundtruth.py (the matrix).

libfaketime (Debian's 0.9.x, checked here): ``FAKETIME="+0.25"`` shifts the wall clock by +250 ms
(``"+250ms"`` would be 250 *minutes*: m is minutes); ``" x1.0005"`` makes it run 500 ppm fast from the
moment the process starts, so ``fake(t) = t + offset + (rate - 1) (t - start)``. By default it fakes
``CLOCK_MONOTONIC`` too, and then answers it with the faked *wall* time (an epoch-sized monotonic clock)
and scales sleeps by the rate: ``FAKETIME_DONT_FAKE_MONOTONIC=1`` leaves the backend's monotonic clock
(its timers, watchdog, uptime) alone, so only the clock the tracker stamps with is off, as on a robot
whose wall clock is. ``FAKETIME_NO_CACHE=1`` makes it re-read its settings on every call.
"""

from __future__ import annotations

import bisect
import glob
import os
import tempfile
import time
from dataclasses import dataclass, field

from arbiter_core import stats
from arbiter_tui.latency.clocksync import LatencyMeter

from .backend import BackendProc, start_backend
from .delayproxy import DelayProxy, Delays
from .waits import wait_for

# Debian's faketime package, on any architecture (x86_64-linux-gnu, aarch64-linux-gnu, ...)
FAKETIME_LIB = next(iter(sorted(glob.glob("/usr/lib/*/faketime/libfaketime.so.1"))), "")


def faketime_available() -> bool:
    return bool(FAKETIME_LIB) and os.path.exists(FAKETIME_LIB)


def faketime_spec(offset_ms: float, drift_ppm: float = 0.0) -> str:
    spec = f"{offset_ms / 1000.0:+.6f}"
    if drift_ppm:
        spec += f" x{1.0 + drift_ppm * 1e-6:.7f}"
    return spec


def faketime_env(offset_ms: float, drift_ppm: float = 0.0, spec_file: str | None = None) -> dict[str, str]:
    """The environment that runs a process with its wall clock ``offset_ms`` off and ``drift_ppm`` fast;
    with ``spec_file`` the setting is read from that file on every call (rewrite it to step the clock)."""
    env = {"LD_PRELOAD": FAKETIME_LIB, "FAKETIME_NO_CACHE": "1", "FAKETIME_DONT_FAKE_MONOTONIC": "1"}
    if spec_file is None:
        env["FAKETIME"] = faketime_spec(offset_ms, drift_ppm)
    else:
        with open(spec_file, "w") as f:
            f.write(faketime_spec(offset_ms, drift_ppm) + "\n")
        env["FAKETIME_TIMESTAMP_FILE"] = spec_file
    return env


@dataclass(frozen=True)
class Case:
    name: str
    offset_ms: float = 0.0  # the backend's wall clock minus ours
    drift_ppm: float = 0.0  # how fast it runs away
    forward_ms: float = 0.0  # console -> rosbridge
    back_ms: float = 0.0  # rosbridge -> console
    jitter_ms: float = 0.0  # uniform [0, jitter] more on each chunk, each direction
    seconds: float = 10.0
    rate_hz: float = 20.0
    step_ms: float = 0.0  # the backend's clock steps by this much...
    step_at_s: float = 0.0  # ...this long into the measurement (libfaketime's timestamp file)
    jitter_kind: str = "uniform"  # or "halfnormal": |N(0, jitter_ms)|
    jitter_back: bool = True  # False: only the commands' direction is jittered
    stall_s: float = 0.0  # the link holds every byte this long...
    stall_at_s: float = 0.0  # ...this long into the measurement
    lost_after_s: float = 2.0  # the meter's: unreported this long, a command counts as lost


@dataclass
class Measured:
    case: Case
    base_rtt_ms: float  # the path without injected delay (proxy, sockets, bridge, tracker)
    rtt_p50_ms: float
    offset_ms: float
    offset_bound_ms: float
    true_offset_ms: float
    drift_ppm: float | None
    drift_bound_ppm: float | None
    corrected_p50_ms: float
    corrected_p50_lo_ms: float
    corrected_p50_hi_ms: float
    jitter_ms: float
    raw_p50_ms: float
    matched: int
    extra: dict = field(default_factory=dict)
    samples: list = field(default_factory=list)  # the meter's Samples (live offset, bound, at_s)
    started_wall: float = 0.0  # our wall clock when the faked backend started (its drift's origin)
    wall_minus_mono: float = 0.0  # our wall clock minus our monotonic clock during the run
    stepped_at: float | None = None  # monotonic: when the backend's clock was stepped
    expire_calls: list = field(default_factory=list)  # monotonic times of meter.expire()
    max_lost: int = 0  # the meter's lost count at its highest during the run
    lost: int = 0
    late: int = 0
    jitter_drawn_ms: list = field(default_factory=list)  # what the proxy drew, forward direction

    def true_offset_at(self, at_mono: float) -> float:
        """The backend's clock minus ours at our monotonic time ``at_mono``: what libfaketime was told."""
        c = self.case
        step = c.step_ms if self.stepped_at is not None and at_mono >= self.stepped_at else 0.0
        return c.offset_ms + step + c.drift_ppm * 1e-3 * (at_mono + self.wall_minus_mono - self.started_wall)

    @property
    def jitter_p50_ms(self) -> float:
        """The median of the jitter injected on one direction: half the width (uniform) or 0.674 sigma."""
        c = self.case
        return c.jitter_ms * (0.6745 if c.jitter_kind == "halfnormal" else 0.5)

    @property
    def true_rtt_ms(self) -> float:
        c = self.case
        j = self.jitter_p50_ms * (2 if c.jitter_back else 1)
        return c.forward_ms + c.back_ms + j + self.base_rtt_ms

    @property
    def true_one_way_ms(self) -> float:
        """The injected forward delay (and median jitter) plus half the base path (symmetric on loopback)."""
        c = self.case
        return c.forward_ms + self.jitter_p50_ms + self.base_rtt_ms / 2

    @property
    def offset_error_ms(self) -> float:
        return self.offset_ms - self.true_offset_ms

    @property
    def offset_bound_holds(self) -> bool:
        return abs(self.offset_error_ms) <= self.offset_bound_ms

    @property
    def one_way_in_interval(self) -> bool:
        return self.corrected_p50_lo_ms <= self.true_one_way_ms <= self.corrected_p50_hi_ms

    def windows(self, window_s: float = 1.0, after: float | None = None) -> tuple[int, int, int]:
        """(windows, offset bound held, one-way interval held): the last command of each second."""
        samples = sorted(self.samples, key=lambda s: s.at_s)
        if not samples:
            return 0, 0, 0
        t0 = samples[0].at_s
        last: dict[int, object] = {}
        for s in samples:
            if after is None or s.at_s >= after:
                last[int((s.at_s - t0) // window_s)] = s
        n = off_ok = ow_ok = 0
        for s in last.values():
            live = s.raw_ms - s.corrected_ms
            truth = self.true_offset_at(s.at_s)
            true_ow = s.raw_ms - truth
            lo, hi = max(s.corrected_ms - s.bound_ms, 0.0), min(s.corrected_ms + s.bound_ms, s.delay_ms)
            n += 1
            off_ok += abs(live - truth) <= s.bound_ms
            ow_ok += lo <= true_ow <= hi
        return n, off_ok, ow_ok

    def lost_then_late_expected(self) -> int:
        """Commands whose report came after an expiry pass past their deadline: what must count lost, then
        late."""
        calls = self.expire_calls
        n = 0
        for s in self.samples:
            sent = s.at_s - s.rtt_ms / 2000.0
            arrival = sent + s.rtt_ms / 1000.0
            i = bisect.bisect_right(calls, sent + self.case.lost_after_s)
            n += i < len(calls) and calls[i] < arrival
        return n


def before_issue_33(samples: list, window_s: float = 64.0) -> tuple[float, float, float]:
    """What the meter on main showed from the same exchanges: the offset of the lowest-RTT sample of
    the last 64 s (``raw - rtt / 2``: the tracker's own time inside), each sample corrected with the
    estimate at its arrival. Returns (final offset, corrected one-way p50, jitter of corrected)."""
    window: list[tuple[float, float, float]] = []  # (arrival, offset, rtt)
    corrected = []
    for x in samples:
        arrival = x.at_s + x.rtt_ms / 2000.0
        window = [w for w in window if w[0] >= arrival - window_s] + [
            (arrival, x.raw_ms - x.rtt_ms / 2, x.rtt_ms)
        ]
        best = min(window, key=lambda w: w[2])
        corrected.append(x.raw_ms - best[1])
    n = len(corrected)
    mean = sum(corrected) / n
    jitter = (sum((c - mean) ** 2 for c in corrected) / n) ** 0.5
    return best[1], stats.percentile(corrected, 0.5), jitter


def measure(case: Case, base_rtt_ms: float | None = None, backend_args: tuple[str, ...] = ()) -> Measured:
    """Run ``case``: a faked backend, the proxy, the console's link sending ``rate_hz`` commands for
    ``seconds``; the figures its meter gives against the injected truth. ``base_rtt_ms`` None: this is
    the base measurement itself (its own rtt p50)."""
    from arbiter_tui.link.base import CONNECTED
    from arbiter_tui.link.rosbridge import RosLink

    spec_file = None
    if case.step_ms:
        fd, spec_file = tempfile.mkstemp(prefix="faketime-", suffix=".rc")
        os.close(fd)
    faked = case.offset_ms or case.drift_ppm or case.step_ms
    env = faketime_env(case.offset_ms, case.drift_ppm, spec_file) if faked else {}
    started_wall = time.time()
    backend: BackendProc = start_backend("--no-sim", *backend_args, env=env)
    delays = Delays(case.forward_ms, case.back_ms, case.jitter_ms, case.jitter_kind, case.jitter_back)
    proxy = DelayProxy(backend.bridge_port, delays)
    link = RosLink("127.0.0.1", proxy.port)
    try:
        if not wait_for(lambda: link.state == CONNECTED, timeout=15):
            raise RuntimeError(f"{case.name}: the link did not connect")
        # warm up (subscriptions in place, first reports back), then measure from a fresh meter
        for _ in range(10):
            link.send(0.0, 0.0)
            time.sleep(0.05)
        wait_for(lambda: link.telemetry.meter.matched >= 5, timeout=5)
        meter = link.telemetry.meter = LatencyMeter(
            history=100_000, offset_window_s=3600.0, lost_after_s=case.lost_after_s
        )
        proxy.jitter_drawn[0].clear()
        n = int(case.seconds * case.rate_hz)
        t = t_start = time.monotonic()
        stepped_at = None
        stalled = False
        expire_calls: list[float] = []
        max_lost = 0

        def expire() -> None:  # as the console's session does, but every tick: lost is noticed promptly
            nonlocal max_lost
            now = time.monotonic()
            meter.expire(now)
            expire_calls.append(now)
            max_lost = max(max_lost, meter.lost)

        for _ in range(n):
            t += 1.0 / case.rate_hz
            time.sleep(max(0.0, t - time.monotonic()))
            expire()
            if case.stall_s and not stalled and t - t_start >= case.stall_at_s:
                proxy.stall(case.stall_s)
                stalled = True
            if spec_file is not None and stepped_at is None and t - t_start >= case.step_at_s:
                with open(spec_file, "w") as f:
                    f.write(faketime_spec(case.offset_ms + case.step_ms, case.drift_ppm) + "\n")
                stepped_at = time.monotonic()
            link.send(0.0, 0.0)
        deadline = time.monotonic() + 5 + (case.forward_ms + case.back_ms) / 100 + case.stall_s
        while meter.matched + meter.lost < n and time.monotonic() < deadline:
            time.sleep(0.02)
            expire()
        s = meter.summary()
        est = meter.offset()
        assert est is not None and s.n, f"{case.name}: no round trips"
        # the truth at the estimate's time (the newest exchange: monotonic -> our wall clock)
        last_at = max(x.at_s for x in meter.samples())
        wall = last_at + (time.time() - time.monotonic())
        true_offset = case.offset_ms + case.step_ms + case.drift_ppm * 1e-3 * (wall - started_wall)
        wall_minus_mono = time.time() - time.monotonic()
        rtt = [x.rtt_ms for x in meter.samples()]
        rtt_p50 = stats.percentile(rtt, 0.5)
        return Measured(
            case=case,
            base_rtt_ms=rtt_p50 if base_rtt_ms is None else base_rtt_ms,
            rtt_p50_ms=rtt_p50,
            offset_ms=est.offset_ms,
            offset_bound_ms=est.uncertainty_ms,
            true_offset_ms=true_offset,
            drift_ppm=est.drift_ppm,
            drift_bound_ppm=est.drift_bound_ppm,
            corrected_p50_ms=s.corrected_p50_ms or 0.0,
            corrected_p50_lo_ms=s.corrected_p50_lo_ms or 0.0,
            corrected_p50_hi_ms=s.corrected_p50_hi_ms or 0.0,
            jitter_ms=s.jitter_ms or 0.0,
            raw_p50_ms=s.raw_p50_ms or 0.0,
            matched=meter.matched,
            extra={
                "before": before_issue_33(meter.samples()),
                "steps": est.steps,
                "lost": meter.lost,
                # how long after the step the model re-anchored (s)
                "reanchored_after_s": None
                if stepped_at is None or not meter.clock.steps
                else meter.clock.steps[-1][0] - stepped_at,
            },
            samples=meter.samples(),
            started_wall=started_wall,
            wall_minus_mono=wall_minus_mono,
            stepped_at=stepped_at,
            expire_calls=expire_calls,
            max_lost=max_lost,
            lost=meter.lost,
            late=meter.late,
            jitter_drawn_ms=list(proxy.jitter_drawn[0]),
        )
    finally:
        link.close()
        proxy.close()
        backend.stop()
        if spec_file is not None:
            os.unlink(spec_file)
