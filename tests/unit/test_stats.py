"""Golden values for the one definition of each statistic, checked by hand."""

import math
import random

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from arbiter_core import stats as S
from arbiter_core.record import latency_stats


def seed_p95(values):
    """Plain transcription of the seed: sorted[Math.floor(n * 0.95)] || 0."""
    s = sorted(values)
    n = len(s)
    return s[math.floor(n * 0.95)] if n else 0


def test_empty_series_is_all_zero():
    assert S.mean([]) == 0.0
    assert S.pstdev([]) == 0.0
    assert S.p95([]) == 0.0
    assert S.minimum([]) == 0.0
    assert S.maximum([]) == 0.0
    assert S.path_length([], []) == 0.0
    assert S.summarize([]) == S.Summary(0, 0.0, 0.0, 0.0, 0.0, 0.0)


def test_single_sample():
    assert S.mean([3.5]) == 3.5
    assert S.pstdev([3.5]) == 0.0
    assert S.p95([3.5]) == 3.5  # floor(1 * 0.95) = 0
    assert S.path_length([1.0], [2.0]) == 0.0


def test_mean_and_population_stddev_divide_by_n():
    data = [2, 4, 4, 4, 5, 5, 7, 9]  # mean 5, squared deviations sum 32, 32/8 = 4
    assert S.mean(data) == 5.0
    assert S.pstdev(data) == 2.0  # the sample std (divide by n-1) would be 2.138...


def test_p95_index_rule_at_20_and_100():
    assert S.p95_index(20) == 19
    assert S.p95_index(100) == 95
    assert S.p95_index(7) == 6  # floor(6.65)
    twenty = list(range(1, 21))
    random.Random(1).shuffle(twenty)
    assert S.p95(twenty) == 20.0  # sorted[19]
    hundred = list(range(1, 101))
    random.Random(2).shuffle(hundred)
    assert S.p95(hundred) == 96.0  # sorted[95], not the interpolated 95.05


def test_min_max():
    assert S.minimum([3, -1, 2]) == -1.0
    assert S.maximum([3, -1, 2]) == 3.0


def test_path_length_sums_consecutive_hypot():
    # (0,0)->(3,4) is 5, standing still is 0, (3,4)->(6,8) is 5
    assert S.path_length([0, 3, 3, 6], [0, 4, 4, 8]) == 10.0


@given(st.lists(st.floats(-1e6, 1e6, allow_nan=False), max_size=300))
def test_p95_matches_the_seeds_sort_for_any_input(values):
    assert S.p95(values) == seed_p95(values)


@given(st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=1, max_size=200))
def test_mean_and_stddev_match_the_seeds_reduce(values):
    n = len(values)
    avg = sum(values) / n
    var = sum((v - avg) ** 2 for v in values) / n
    assert S.mean(values) == pytest.approx(avg, abs=1e-9)
    assert S.pstdev(values) == pytest.approx(math.sqrt(var), abs=1e-6)


def test_latency_stats_shape_and_nulls_when_empty():
    assert latency_stats([]) == {
        "count": 0,
        "mean_ms": None,
        "min_ms": None,
        "max_ms": None,
        "p95_ms": None,
        "stddev_ms": None,
    }
    got = latency_stats([0.1, 0.2, 0.3, 0.4])
    assert got == {
        "count": 4,
        "mean_ms": 0.25,
        "min_ms": 0.1,
        "max_ms": 0.4,
        "p95_ms": 0.4,
        "stddev_ms": 0.1118,
    }


def test_numpy_arrays_are_accepted_without_copy_semantics_changing_results():
    a = np.array([5.0, 1.0, 3.0])
    assert S.p95(a) == 5.0
    assert list(a) == [5.0, 1.0, 3.0]  # p95 must not reorder the caller's array


@pytest.mark.parametrize("n", [50_000, 100_003, 1_000_000])
@pytest.mark.parametrize(
    "shape", ["random", "ascending", "descending", "constant", "two_values", "top_tied", "sawtooth", "spike"]
)
def test_large_percentiles_are_exactly_the_seeds_sorted_index(n, shape):
    """The pre-filtered selection for large arrays gives exactly sorted(values)[floor(n q)], whatever the
    order or the ties (orders that defeat a strided sample included)."""
    rng = np.random.default_rng(n)
    i = np.arange(n, dtype=np.float64)
    a = {
        "random": rng.normal(1.0, 0.5, n),
        "ascending": i,
        "descending": i[::-1].copy(),
        "constant": np.full(n, 0.25),
        "two_values": np.where(rng.random(n) < 0.96, 0.0, 1.0),
        "top_tied": np.where(i >= 0.9 * n, 7.0, i),
        "sawtooth": i % 4097,
        "spike": np.where(i % 4096 == 0, 1e6, rng.random(n)),
    }[shape]
    for q in (0.5, 0.95, 0.99):
        assert S.percentile(a, q) == float(np.sort(a)[math.floor(n * q)]), q
