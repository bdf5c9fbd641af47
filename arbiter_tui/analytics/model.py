"""The seed's data model and its one formula: DataPoint, AnalyticsStats, ``compute_stats``.

Pure: numpy and ``arbiter_core.stats``, no I/O. The store (the ring buffer), the runs (what the comparison
compares) and the exports all build on these definitions.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Sequence
from dataclasses import asdict, dataclass, fields
from typing import TypeVar

import numpy as np

from arbiter_core import stats as S

FIELDS = (
    "timestamp",
    "x",
    "y",
    "theta",
    "linearVel",
    "angularVel",
    "distanceError",
    "headingError",
    "algorithm",
    "latencyMs",
)
"""DataPoint fields in the seed's order -- the CSV header's first ten columns."""
EXTRA_FIELDS = ("runId", "gap")
"""Ours, after the seed's: the run id (empty/null outside a run), and whether the sample follows a gap
in the recording (CSV ``1`` or empty)."""

NUMERIC = tuple(f for f in FIELDS if f != "algorithm")
MAX_ALGORITHM_NAME = 64


@dataclass(frozen=True)
class DataPoint:
    timestamp: float  # Date.now() ms
    x: float  # m
    y: float  # m
    theta: float  # rad
    linearVel: float  # commanded m/s
    angularVel: float  # commanded rad/s
    distanceError: float  # m
    headingError: float  # rad
    algorithm: str
    latencyMs: float | None  # None when no latency is known (client-side simulation)
    # Beyond the seed: the run this sample belongs to (runs.py); None outside every run. Exports carry
    # it after the seed's columns, so a reader of the seed's format still finds its ten fields.
    runId: int | None = None
    # Beyond the seed: this sample follows a gap in the recording (the link was down, odometry stale, or
    # its pose jumped: a new odometry life). Nothing was recorded in between, and no path length is
    # counted across it (``arbiter_core.stats.path_length``).
    gap: bool = False

    def validate(self) -> None:
        for name in NUMERIC:
            value = getattr(self, name)
            if name == "latencyMs" and value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"DataPoint.{name} must be a number, got {type(value).__name__}")
            if not math.isfinite(value):
                raise ValueError(f"DataPoint.{name} must be finite, got {value}")
        if not isinstance(self.algorithm, str) or not self.algorithm:
            raise ValueError("DataPoint.algorithm must be a non-empty string")
        if len(self.algorithm) > MAX_ALGORITHM_NAME:
            raise ValueError(f"DataPoint.algorithm longer than {MAX_ALGORITHM_NAME} characters")
        if self.runId is not None and (
            isinstance(self.runId, bool) or not isinstance(self.runId, int) or not 1 <= self.runId < 2**32
        ):
            raise ValueError(f"DataPoint.runId must be a positive integer or None, got {self.runId!r}")
        if not isinstance(self.gap, bool):
            raise ValueError(f"DataPoint.gap must be true or false, got {self.gap!r}")

    def as_dict(self) -> dict[str, float | str | None]:
        return asdict(self)


@dataclass(frozen=True)
class AnalyticsStats:
    sampleCount: int
    avgLinearVel: float  # mean |v|
    avgAngularVel: float  # mean |omega|
    maxLinearVel: float  # max |v|
    avgDistanceError: float  # mean e_d
    avgHeadingError: float  # mean |e_theta|
    stdDevError: float  # population std of e_d
    p95Error: float  # seed's p95 of e_d
    totalPathLength: float  # sum of hypot between consecutive samples

    def as_dict(self) -> dict[str, float | int]:
        return asdict(self)


STATS_FIELDS = tuple(f.name for f in fields(AnalyticsStats))
EMPTY_STATS = AnalyticsStats(0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def compute_stats(
    x: np.ndarray,
    y: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    e_d: np.ndarray,
    e_th: np.ndarray,
    path: float | None = None,
    gaps: np.ndarray | None = None,
) -> AnalyticsStats:
    """AnalyticsStats of time-ordered columns (``path`` overrides the path length when given; ``gaps``:
    the samples that follow a gap, whose step is not counted)."""
    n = int(e_d.size)
    if n == 0:
        return EMPTY_STATS
    abs_v = np.abs(v)
    return AnalyticsStats(
        sampleCount=n,
        avgLinearVel=S.mean(abs_v),
        avgAngularVel=S.mean(np.abs(w)),
        maxLinearVel=S.maximum(abs_v),
        avgDistanceError=S.mean(e_d),
        avgHeadingError=S.mean(np.abs(e_th)),
        stdDevError=S.pstdev(e_d),
        p95Error=S.p95(e_d),
        totalPathLength=S.path_length(x, y, gaps) if path is None else path,
    )


def stats_of_points(points: Iterable[DataPoint]) -> AnalyticsStats:
    pts = list(points)

    def col(name: str) -> np.ndarray:
        return np.fromiter((getattr(p, name) for p in pts), dtype=np.float64, count=len(pts))

    gaps = np.fromiter((p.gap for p in pts), dtype=bool, count=len(pts))
    return compute_stats(
        col("x"), col("y"), col("linearVel"), col("angularVel"), col("distanceError"), col("headingError"),
        gaps=gaps,
    )  # fmt: skip


Label = TypeVar("Label", bound=Hashable)


def grouped_stats(
    cols: dict[str, np.ndarray],
    labels: Sequence[Label],
    stretch: np.ndarray | None = None,
    gaps: np.ndarray | None = None,
) -> dict[Label, AnalyticsStats]:
    """AnalyticsStats per label over time-ordered columns (first-seen order of the labels).

    A group's path length counts only steps between two samples that are next to each other in the
    recording, carry the same label and (when ``stretch`` is given, e.g. the run ids) the same stretch: a
    path never spans a gap between separate stretches, such as idle samples before and after a run,
    nor a gap in the recording (``gaps``: the samples that follow one).
    """
    x, y = cols["x"], cols["y"]
    steps = S.step_lengths(x, y)  # once, shared by every group
    order = list(dict.fromkeys(labels))
    index = {label: i for i, label in enumerate(order)}
    codes = np.fromiter((index[label] for label in labels), dtype=np.int64, count=len(labels))
    joined = codes[1:] == codes[:-1]
    if stretch is not None:
        joined &= stretch[1:] == stretch[:-1]
    if gaps is not None:
        joined &= ~np.asarray(gaps, dtype=bool)[1:]
    out: dict[Label, AnalyticsStats] = {}
    for i, label in enumerate(order):
        mask = codes == i
        path = float(steps[joined & mask[1:]].sum())
        out[label] = compute_stats(
            x[mask], y[mask], cols["linearVel"][mask], cols["angularVel"][mask],
            cols["distanceError"][mask], cols["headingError"][mask], path=path,
        )  # fmt: skip
    return out


def columns_of(points: Sequence[DataPoint]) -> dict[str, np.ndarray]:
    """The numeric columns of a list of points (latency: NaN where unknown)."""
    out = {}
    for name in NUMERIC:
        out[name] = np.fromiter(
            (math.nan if (v := getattr(p, name)) is None else v for p in points), dtype=np.float64,
            count=len(points),
        )  # fmt: skip
    return out
