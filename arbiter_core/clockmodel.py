"""A model of another host's clock from NTP-style exchanges: offset *and* drift, with bounds (pure).

One exchange gives four times: ``t0`` our send (wall), ``t1`` the tracker's receive and ``t2`` its
report (its wall clock), ``t3`` our receipt. We measure ``t3 - t0`` on the monotonic clock (the round
trip), so a step of our own wall clock never enters it. NTP then gives

* ``delay = (t3 - t0) - (t2 - t1)``: the time on the wire, the tracker's own time taken out;
* ``offset = ((t1 - t0) + (t2 - t3)) / 2``: its clock minus ours, assuming symmetric paths;
* and, whatever the asymmetry, the true offset lies in ``offset ± delay / 2`` (each direction takes
  between 0 and ``delay``). This bound is hard: it holds for every honest exchange.

Why a model, not the lowest-delay sample of a window (what the console used before): two crystals
drift apart at tens to hundreds of ppm, so the offset is a line, not a constant. The best sample of a
64 s window is up to 64 s old, and at 500 ppm that is 32 ms of error. This follows chrony and NTP's
clock filter + frequency loop, in a form that can be reasoned about:

1. **minimum-delay filter per time bucket** (``bucket_s``): queueing only ever adds delay, and adds it
   asymmetrically, so in each bucket the exchange with the least delay has the tightest bound and the
   least bias; the others are dropped. A bucket whose best delay is still far above the window's best
   (over ``max_delay_ratio`` times it plus ``delay_slack_ms``: every exchange of it queued, as in a
   flood) is left out of the fit, as chrony's ``maxdelayratio`` does;
2. **weighted least-squares line** through the buckets of the last ``window_s`` (weights
   ``1 / (delay/2)^2``: a tight sample counts more), refitted once without points whose residual is
   over three robust deviations (MAD): a bucket whose every exchange queued cannot bend the line. Its
   slope is the drift (ppm = µs of offset per s); chrony does the same regression (plus a runs test to
   pick how many points), NTP's PLL converges on the same figure more slowly;
3. **step detection**: a new exchange *contradicts* the model when its hard interval
   (``offset ± delay/2``) and the model's own (``prediction ± bound``) do not overlap. An honest
   exchange can never do that while the model is right, so ``step_after`` contradictions in a row
   (same sign) mean the clock stepped (or the drift changed): the history is dropped and the model
   re-anchors on those exchanges instead of averaging the step in over a window.

The bound of the offset at time ``x``: for every bucket point i, the truth at ``x_i`` is within
``delay_i / 2`` of ``offset_i``, and moves by the true drift from there, so
``|truth(x) - model(x)| <= |residual_i| + delay_i / 2 + drift_error * |x - x_i|``; the bound is the
least of these over the points. ``drift_error`` is the 99.7 % interval of the fitted slope (a
statistical, not a hard, part): Student's t for ``points - 2`` degrees of freedom times its standard
error, as the scatter is estimated from those few points (3 standard errors for many points; with 5
points, 10 s of 2 s buckets, it is 6.6, and 3 would be exceeded about one run in ten under jitter);
or, before a slope can be fitted, ``max_drift_ppm``: an extrapolation that admits any plausible crystal.

Times: ``at_s`` is our monotonic clock in seconds (where the exchange happened, its midpoint);
offsets and delays are in ms. No I/O, no clock read here: callers pass every time in.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

MAD_TO_SIGMA = 1.4826


@dataclass(frozen=True, slots=True)
class Exchange:
    at_s: float  # our monotonic time of the exchange's midpoint, s
    offset_ms: float  # their clock minus ours, symmetric-path estimate
    delay_ms: float  # round trip minus the time the other side held the message; >= 0

    @property
    def half_ms(self) -> float:
        """Half the delay: the hard bound of ``offset_ms``, whatever the path asymmetry."""
        return self.delay_ms / 2.0


def ntp_exchange(up_ms: float, held_ms: float, rtt_ms: float, sent_at_s: float) -> Exchange:
    """The exchange of a command whose ``t1 - t0`` was ``up_ms`` (their receive stamp minus our send
    stamp: the seed's raw one-way figure), held ``held_ms = t2 - t1`` on their side, and whose report
    came back ``rtt_ms`` after it left (our monotonic clock, sent at ``sent_at_s``). Differences, not
    epoch stamps, so that no precision is lost (a float of epoch ms resolves only ~0.24 µs).

    ``t3 = t0 + rtt``, so ``offset = ((t1 - t0) + (t2 - t3)) / 2 = up + (held - rtt) / 2`` and
    ``delay = rtt - held``. A negative ``held`` (their clock stepped back in between) counts as zero.
    """
    held = min(max(held_ms, 0.0), max(rtt_ms, 0.0))
    return Exchange(sent_at_s + rtt_ms / 2000.0, up_ms + (held - rtt_ms) / 2.0, max(rtt_ms - held, 0.0))


@dataclass(frozen=True, slots=True)
class ClockEstimate:
    at_s: float
    offset_ms: float  # their clock minus ours, at at_s
    bound_ms: float  # the truth lies within offset_ms ± bound_ms
    drift_ppm: float | None  # None: too short a span to fit a slope
    drift_bound_ppm: float | None  # the drift's error (its 99.7 % interval: ~3 standard errors)
    best_delay_ms: float  # the least delay among the points used
    points: int  # bucket minima in the model
    epoch: int  # how many times the model re-anchored (clock steps)

    def significant(self, threshold_ms: float) -> bool:
        """The offset surely exceeds ``threshold_ms``: even at the edge of its bound."""
        return abs(self.offset_ms) - self.bound_ms > threshold_ms

    def seconds_until(self, threshold_ms: float) -> float | None:
        """When the drift takes |offset| past ``threshold_ms`` (s from ``at_s``); None if it does not
        (no drift known, drift not significant, moving away, or already past)."""
        if self.drift_ppm is None or self.drift_bound_ppm is None or abs(self.offset_ms) >= threshold_ms:
            return None
        if abs(self.drift_ppm) <= self.drift_bound_ppm:
            return None
        rate = self.drift_ppm / 1000.0  # ms per s
        target = threshold_ms if rate > 0 else -threshold_ms
        dt = (target - self.offset_ms) / rate
        return dt if dt > 0 else None


@dataclass(frozen=True, slots=True)
class _Fit:
    x0: float
    a: float  # offset at x0
    b: float  # slope, ms per s
    b_err: float  # ms per s (the slope's 99.7 % half-interval, or the max-drift allowance)
    fitted: bool  # a slope was fitted (else b == 0 and b_err is the allowance)
    points: tuple[tuple[float, float, float], ...]  # (x, offset, half-delay) used
    residuals: tuple[float, ...]

    def predict(self, x: float) -> float:
        return self.a + self.b * (x - self.x0)

    def bound(self, x: float) -> float:
        pairs = zip(self.points, self.residuals, strict=True)
        return min(abs(r) + h + self.b_err * abs(x - px) for (px, _o, h), r in pairs)


class ClockModel:
    def __init__(
        self,
        bucket_s: float = 2.0,
        window_s: float = 120.0,
        min_span_s: float = 6.0,
        max_drift_ppm: float = 500.0,
        max_delay_ratio: float = 3.0,
        delay_slack_ms: float = 1.0,
        step_after: int = 3,
        tolerance_ms: float = 0.05,
    ) -> None:
        if bucket_s <= 0 or window_s < bucket_s or step_after < 1:
            raise ValueError("bucket_s > 0, window_s >= bucket_s and step_after >= 1 are required")
        self.bucket_s = bucket_s
        self.window_s = window_s
        self.min_span_s = min_span_s
        self.max_drift_ppm = max_drift_ppm  # NTP's limit on a clock's frequency error
        self.max_delay_ratio = max_delay_ratio
        self.delay_slack_ms = delay_slack_ms
        self.step_after = step_after
        self.tolerance_ms = tolerance_ms
        self._buckets: deque[tuple[int, Exchange]] = deque()  # (bucket index, its least-delay exchange)
        self._fit: _Fit | None = None
        self._contradictions: list[Exchange] = []
        self._contra_sign = False
        self.epoch = 0
        self.anchor_s = -math.inf  # where the current epoch starts (its first exchange)
        self.steps: list[tuple[float, float]] = []  # (at_s, size ms) of each re-anchor
        self.added = 0

    # -- input ----------------------------------------------------------------------------------
    def add(self, ex: Exchange) -> bool:
        """Take one exchange; True when it made the model re-anchor (a clock step)."""
        self.added += 1
        fit = self._fit
        if fit is not None:
            miss = ex.offset_ms - fit.predict(ex.at_s)
            if abs(miss) > ex.half_ms + fit.bound(ex.at_s) + self.tolerance_ms:
                sign = miss > 0
                same_way = bool(self._contradictions) and sign == self._contra_sign
                self._contradictions = [*self._contradictions, ex] if same_way else [ex]
                self._contra_sign = sign
                if len(self._contradictions) >= self.step_after:
                    self._reanchor(ex.at_s, miss)
                    return True
                return False  # held back: a step, or one of a few bad exchanges
            self._contradictions = []
        if self._put(ex):
            self._refit()
        return False

    def _reanchor(self, at_s: float, miss: float) -> None:
        held, self._contradictions = self._contradictions, []
        self._buckets.clear()
        self.anchor_s = min(ex.at_s for ex in held)
        self.epoch += 1
        self.steps.append((at_s, miss))
        for ex in held:
            self._put(ex)
        self._refit()

    def _put(self, ex: Exchange) -> bool:
        """Into its bucket if it has the least delay there; True when the buckets changed."""
        idx = math.floor(ex.at_s / self.bucket_s)
        changed = True
        if self._buckets and self._buckets[-1][0] == idx:
            changed = ex.delay_ms < self._buckets[-1][1].delay_ms
            if changed:
                self._buckets[-1] = (idx, ex)
        elif not self._buckets or idx > self._buckets[-1][0]:
            self._buckets.append((idx, ex))
        else:  # out of order (a late report): find its bucket
            for i, (j, old) in enumerate(self._buckets):
                if j == idx:
                    changed = ex.delay_ms < old.delay_ms
                    if changed:
                        self._buckets[i] = (idx, ex)
                    break
                if j > idx:
                    self._buckets.insert(i, (idx, ex))
                    break
        newest = self._buckets[-1][1].at_s
        while self._buckets[0][1].at_s < newest - self.window_s:
            self._buckets.popleft()
            changed = True
        return changed

    def _refit(self) -> None:
        if not self._buckets:
            self._fit = None
            return
        best = min(ex.delay_ms for _i, ex in self._buckets)
        limit = best * self.max_delay_ratio + self.delay_slack_ms
        pts = [(ex.at_s, ex.offset_ms, ex.half_ms) for _i, ex in self._buckets if ex.delay_ms <= limit]
        self._fit = self._fit_line(pts)

    def _fit_line(self, pts: list[tuple[float, float, float]]) -> _Fit:
        allowance = self.max_drift_ppm / 1000.0
        span = pts[-1][0] - pts[0][0]
        if len(pts) < 3 or span < self.min_span_s:
            best = min(pts, key=lambda p: p[2])
            flat = tuple(o - best[1] for _x, o, _h in pts)
            return _Fit(best[0], best[1], 0.0, allowance, False, tuple(pts), flat)
        fit = _wls(pts)
        res = [o - (fit[0] + fit[1] * (x - fit[3])) for x, o, _h in pts]
        mad = _median([abs(r - _median(res)) for r in res]) * MAD_TO_SIGMA
        cut = max(3.0 * mad, self.tolerance_ms)
        kept = [p for p, r in zip(pts, res, strict=True) if abs(r) <= cut]
        if len(kept) >= 3 and len(kept) < len(pts) and kept[-1][0] - kept[0][0] >= self.min_span_s:
            fit = _wls(kept)
            pts = kept
        a, b, b_se, x0 = fit
        residuals = tuple(o - (a + b * (x - x0)) for x, o, _h in pts)
        # no wider than "any plausible crystal" allows: the true drift is within ± max_drift_ppm
        b_err = min(t_997(len(pts) - 2) * b_se, abs(b) + allowance)
        return _Fit(x0, a, b, b_err, True, tuple(pts), residuals)

    # -- reading ---------------------------------------------------------------------------------
    def estimate(self, at_s: float) -> ClockEstimate | None:
        fit = self._fit
        if fit is None:
            return None
        return ClockEstimate(
            at_s=at_s,
            offset_ms=fit.predict(at_s),
            bound_ms=fit.bound(at_s),
            drift_ppm=fit.b * 1000.0 if fit.fitted else None,
            drift_bound_ppm=fit.b_err * 1000.0 if fit.fitted else None,
            best_delay_ms=min(h for _x, _o, h in fit.points) * 2.0,
            points=len(fit.points),
            epoch=self.epoch,
        )

    def offset_at(self, at_s: float) -> float | None:
        return None if self._fit is None else self._fit.predict(at_s)

    def offsets_and_bounds(self, xs: Sequence[float]) -> tuple[np.ndarray, np.ndarray] | None:
        """The model's offset and its bound at each of ``xs`` (vectorised: the summary's hindsight)."""
        fit = self._fit
        if fit is None:
            return None
        x = np.asarray(xs, dtype=np.float64)
        px = np.array([p[0] for p in fit.points])
        slack = np.array([abs(r) + p[2] for p, r in zip(fit.points, fit.residuals, strict=True)])
        bounds = (slack[:, None] + fit.b_err * np.abs(x[None, :] - px[:, None])).min(axis=0)
        return fit.a + fit.b * (x - fit.x0), bounds


# Student's t, two-sided 99.73 % (the "3 sigma" level), for 1..30 degrees of freedom
_T997 = (
    235.78, 19.21, 9.22, 6.62, 5.51, 4.90, 4.53, 4.28, 4.09, 3.96, 3.85, 3.76, 3.69, 3.64, 3.59,
    3.54, 3.51, 3.48, 3.45, 3.42, 3.40, 3.38, 3.36, 3.34, 3.33, 3.32, 3.30, 3.29, 3.28, 3.27,
)  # fmt: skip


def t_997(dof: int) -> float:
    """The multiple of a standard error that a 99.73 % interval takes with ``dof`` degrees of freedom
    (the scatter estimated from the data); tends to 3 (beyond 30: the first-order expansion)."""
    if dof < 1:
        return math.inf
    return _T997[dof - 1] if dof <= len(_T997) else 3.0 + 7.5 / dof


def _median(values: Sequence[float]) -> float:
    s = sorted(values)
    n = len(s)
    return s[n // 2] if n % 2 else (s[n // 2 - 1] + s[n // 2]) / 2.0


def _wls(pts: list[tuple[float, float, float]]) -> tuple[float, float, float, float]:
    """Weighted least squares ``offset = a + b (x - x0)``; returns ``(a, b, se(b), x0)``, x0 the
    weighted mean of x (so a and b are uncorrelated)."""
    w = [1.0 / max(h, 0.01) ** 2 for _x, _o, h in pts]
    sw = sum(w)
    x0 = sum(wi * x for wi, (x, _o, _h) in zip(w, pts, strict=True)) / sw
    y0 = sum(wi * o for wi, (_x, o, _h) in zip(w, pts, strict=True)) / sw
    sxx = sum(wi * (x - x0) ** 2 for wi, (x, _o, _h) in zip(w, pts, strict=True))
    sxy = sum(wi * (x - x0) * (o - y0) for wi, (x, o, _h) in zip(w, pts, strict=True))
    b = sxy / sxx if sxx > 0 else 0.0
    n = len(pts)
    rss = sum(wi * (o - y0 - b * (x - x0)) ** 2 for wi, (x, o, _h) in zip(w, pts, strict=True))
    # the residual scale comes from the data (weights are relative), never below a 20 µs scatter
    # (the stamps' resolution is 1 µs): points exactly on a line do not make the slope exact
    sigma2 = max(rss / (n - 2) if n > 2 else 0.0, 0.02**2 * sw / n)
    se = math.sqrt(sigma2 / sxx) if sxx > 0 else math.inf
    return y0, b, se, x0
