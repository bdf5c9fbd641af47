"""The one definition of each statistic in the code base.

Every figure the product shows -- the analytics store's AnalyticsStats and the
latency tracker's ``/api/latency`` stats -- is computed by these functions.
They follow the seed exactly:

* mean: ``sum / n``
* standard deviation: population form, the variance divides by ``n``
* p95: sort ascending and take index ``floor(n * 0.95)``; ``0`` when empty

Inputs are numpy float64 arrays (or anything ``np.asarray`` accepts). The p95
selects exactly the element the seed's full sort would put at that index, in
linear time (``np.partition``, on a pre-filtered part of a large array).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
ArrayLike = FloatArray | Sequence[float]
BoolArrayLike = npt.NDArray[np.bool_] | Sequence[bool]


def _arr(values: ArrayLike) -> FloatArray:
    return np.asarray(values, dtype=np.float64)


def p95_index(n: int) -> int:
    """The seed's p95 index: ``floor(n * 0.95)`` (valid for n >= 1)."""
    return math.floor(n * 0.95)


def mean(values: ArrayLike) -> float:
    """Arithmetic mean; 0.0 for no samples (the seed divides by n, guarded)."""
    a = _arr(values)
    if a.size == 0:
        return 0.0
    return float(a.sum() / a.size)


def pstdev(values: ArrayLike) -> float:
    """Population standard deviation: sqrt(sum((x - mean)^2) / n); 0.0 when empty."""
    a = _arr(values)
    if a.size == 0:
        return 0.0
    m = a.sum() / a.size
    d = a - m
    # not np.dot: that is BLAS, whose worker threads spin on a second core long after a large product
    # (measured: ~120 ms of CPU per analytics update at 1M points); a plain sum uses one core
    np.multiply(d, d, out=d)
    return float(math.sqrt(float(d.sum()) / a.size))


def minimum(values: ArrayLike) -> float:
    a = _arr(values)
    return float(a.min()) if a.size else 0.0


def maximum(values: ArrayLike) -> float:
    a = _arr(values)
    return float(a.max()) if a.size else 0.0


def p95(values: ArrayLike) -> float:
    """The seed's 95th percentile: ``sorted(values)[floor(n * 0.95)]``, 0.0 when empty.

    For n >= 1 the index is always < n, so the seed's ``|| 0`` fallback only
    applies to the empty case (and to a p95 value that is itself 0).
    """
    return percentile(values, 0.95)


def percentile(values: ArrayLike, q: float) -> float:
    """The seed's percentile rule for any ``q`` in [0, 1): ``sorted(values)[floor(n * q)]``; 0.0 when empty.

    p50/p99 in the latency figures use it, so every percentile in the product is the seed's.
    """
    if not 0.0 <= q < 1.0:
        raise ValueError(f"q must be in [0, 1), got {q}")
    a = _arr(values)
    n = a.size
    if n == 0:
        return 0.0
    k = p95_index(n) if q == 0.95 else math.floor(n * q)
    return float(_kth_smallest(a, k))


_SELECT_MIN = 50_000  # below this a full np.partition is as fast


def _kth_smallest(a: FloatArray, k: int) -> float:
    """``sorted(a)[k]``, exactly. For a large array: a threshold a little below the answer, estimated
    from an evenly strided sample, keeps the few values at or above it, and the k-th is selected among
    those (one pass and a small partition instead of partitioning everything: ~10x faster at 1M). When
    the estimate misses, the full partition decides."""
    n = a.size
    if n < _SELECT_MIN:
        return float(np.partition(a, k)[k])
    stride = max(1, n // 4096)
    sample = np.sort(a[::stride])
    guess = int(k / n * sample.size) - 2 * int(math.sqrt(sample.size)) - 1  # a margin below the estimate
    if guess > 0:
        threshold = sample[guess]
        above = a[a >= threshold]
        below = n - above.size  # values strictly smaller than the threshold
        if below <= k:
            j = k - below
            return float(np.partition(above, j)[j])
    return float(np.partition(a, k)[k])


def path_length(xs: ArrayLike, ys: ArrayLike, gaps: BoolArrayLike | None = None) -> float:
    """Sum of Euclidean distances between consecutive (x, y) samples. ``gaps`` (booleans, one per
    sample): a sample that follows a gap in the recording (the link was down, the odometry stale or
    reset); the step into it is not counted, since nobody saw the way the robot took."""
    x = _arr(xs)
    y = _arr(ys)
    if x.size < 2:
        return 0.0
    steps = step_lengths(x, y)
    if gaps is not None:
        into_gap = np.asarray(gaps, dtype=bool)[1:]
        if into_gap.any():
            return float(steps[~into_gap].sum())
    return float(steps.sum())


def step_lengths(xs: ArrayLike, ys: ArrayLike) -> FloatArray:
    """Distance of each step between consecutive samples (n - 1 values).

    ``sqrt(dx*dx + dy*dy)`` rather than ``np.hypot``: the same values at robot
    scales, and about 7x faster (hypot guards against overflow we cannot reach).
    """
    x = _arr(xs)
    y = _arr(ys)
    dx = np.subtract(x[1:], x[:-1])
    dy = np.subtract(y[1:], y[:-1])
    np.multiply(dx, dx, out=dx)  # in place: two temporaries instead of six (a million steps: 8 MB each)
    np.multiply(dy, dy, out=dy)
    np.add(dx, dy, out=dx)
    return np.sqrt(dx, out=dx)


@dataclass(frozen=True)
class Summary:
    """count/mean/min/max/p95/stddev of one series (the tracker's stats block)."""

    count: int
    mean: float
    min: float
    max: float
    p95: float
    stddev: float


def summarize(values: ArrayLike) -> Summary:
    a = _arr(values)
    if a.size == 0:
        return Summary(0, 0.0, 0.0, 0.0, 0.0, 0.0)
    return Summary(
        count=int(a.size),
        mean=mean(a),
        min=minimum(a),
        max=maximum(a),
        p95=p95(a),
        stddev=pstdev(a),
    )


# Student's t, 97.5th percentile, for 1..30 degrees of freedom; beyond, interpolated in 1/df to 1.96.
_T975 = (
    12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145,
    2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048,
    2.045, 2.042,
)  # fmt: skip


def t975(df: int) -> float:
    """The two-sided 95 % Student-t critical value for ``df`` >= 1 degrees of freedom."""
    if df < 1:
        raise ValueError(f"degrees of freedom must be >= 1, got {df}")
    if df <= len(_T975):
        return _T975[df - 1]
    return 1.96 + (_T975[-1] - 1.96) * len(_T975) / df  # 2.021 at 60, 1.98 at 120 (tables: 2.000, 1.980)


def mean_ci95(values: ArrayLike) -> tuple[float, float]:
    """(mean, half-width of its 95 % confidence interval): ``t975(n-1) * s / sqrt(n)`` with the sample
    standard deviation ``s`` (divides by n - 1: an estimate from trials, unlike the seed's population
    form). One value: half-width 0 (nothing to estimate a spread from); none: (0, 0)."""
    a = _arr(values)
    n = a.size
    if n == 0:
        return 0.0, 0.0
    m = float(a.sum() / n)
    if n == 1:
        return m, 0.0
    s = math.sqrt(float(((a - m) ** 2).sum()) / (n - 1))
    return m, t975(n - 1) * s / math.sqrt(n)
