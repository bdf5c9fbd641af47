import math
import threading

import numpy as np
import pytest

from arbiter_tui.analytics import store as analytics
from arbiter_tui.analytics.store import FIELDS, AnalyticsStore, DataPoint, stats_of_points

from ..support.points import make_point, random_points


def collecting(**kw) -> AnalyticsStore:
    s = AnalyticsStore(**kw)
    s.start_collection()
    return s


def test_defaults_and_field_names_are_the_seeds():
    s = AnalyticsStore()
    assert (s.is_collecting, s.collection_rate, s.max_data_points, len(s)) == (False, 10.0, 1000, 0)
    assert FIELDS == (
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
    assert [f for f in analytics.AnalyticsStats.__dataclass_fields__] == [
        "sampleCount",
        "avgLinearVel",
        "avgAngularVel",
        "maxLinearVel",
        "avgDistanceError",
        "avgHeadingError",
        "stdDevError",
        "p95Error",
        "totalPathLength",
    ]


def test_no_module_level_store():
    import arbiter_tui.analytics.store as module

    assert not any(isinstance(v, AnalyticsStore) for v in vars(module).values())


def test_not_collecting_drops_points():
    s = AnalyticsStore()
    assert s.record(make_point(0)) is False
    assert len(s) == 0
    s.start_collection()
    assert s.record(make_point(1)) is True
    s.stop_collection()
    assert s.record(make_point(2)) is False
    assert [p.timestamp for p in s.points()] == [make_point(1).timestamp]


def test_ring_buffer_keeps_newest_in_order():
    s = collecting(max_data_points=5)
    for i in range(12):
        s.record(make_point(i))
    assert len(s) == 5
    assert s.total_recorded == 12
    assert [p for p in s.points()] == [make_point(i) for i in range(7, 12)]


@pytest.mark.parametrize("n", [1, 2, 999, 1000, 1001, 2500, 3333])
def test_stats_match_a_plain_recomputation_after_any_amount_of_wrapping(n):
    s = collecting(max_data_points=1000)
    pts = random_points(n, seed=n)
    for p in pts:
        s.record(p)
    kept = pts[-1000:]
    assert s.points() == kept
    got, want = s.stats(), stats_of_points(kept)
    for f in analytics.STATS_FIELDS:
        assert getattr(got, f) == pytest.approx(getattr(want, f), rel=1e-12, abs=1e-12), f


def test_stats_golden_values_by_hand():
    s = collecting()
    rows = [  # x, y, v, w, e_d, e_th
        (0, 0, 0.5, -1.0, 1.0, -0.5),
        (3, 4, -1.0, 0.5, 2.0, 0.5),
        (3, 4, 0.0, 0.0, 3.0, 0.0),
        (6, 8, 0.5, 0.0, 6.0, 1.0),
    ]
    for i, (x, y, v, w, ed, eth) in enumerate(rows):
        s.record(DataPoint(i, x, y, 0.0, v, w, ed, eth, "go_to_goal", None))
    st = s.stats()
    assert st.sampleCount == 4
    assert st.avgLinearVel == 0.5  # (0.5 + 1 + 0 + 0.5) / 4
    assert st.avgAngularVel == 0.375  # (1 + 0.5 + 0 + 0) / 4
    assert st.maxLinearVel == 1.0  # |v| max, sign ignored
    assert st.avgDistanceError == 3.0
    assert st.avgHeadingError == 0.5
    assert st.stdDevError == math.sqrt(14 / 4)  # deviations -2,-1,0,3
    assert st.p95Error == 6.0  # sorted[floor(3.8)] = sorted[3]
    assert st.totalPathLength == 10.0


def test_empty_stats_are_zero():
    s = AnalyticsStore()
    assert s.stats() == analytics.EMPTY_STATS
    assert s.stats().p95Error == 0


def test_stats_by_algorithm_compare_controllers():
    s = collecting()
    s.record(DataPoint(0, 0, 0, 0, 1.0, 0, 1.0, 0, "go_to_goal", None))
    s.record(DataPoint(1, 3, 4, 0, 1.0, 0, 3.0, 0, "go_to_goal", None))
    s.record(DataPoint(2, 100, 100, 0, 0.2, 0, 5.0, 0, "pure_pursuit", None))
    s.record(DataPoint(3, 100, 101, 0, 0.4, 0, 7.0, 0, "pure_pursuit", None))
    by = s.stats_by_algorithm()
    assert list(by) == ["go_to_goal", "pure_pursuit"]
    assert by["go_to_goal"].avgDistanceError == 2.0
    assert by["go_to_goal"].totalPathLength == 5.0
    assert by["pure_pursuit"].totalPathLength == 1.0  # the jump between algorithms counts for neither
    assert by["pure_pursuit"].avgLinearVel == pytest.approx(0.3)


def test_every_change_a_reader_sees_moves_the_version():
    s = AnalyticsStore()
    seen = [s.version]
    for change in (s.start_collection, lambda: s.record(make_point(0)), s.clear, s.stop_collection):
        change()
        seen.append(s.version)
    assert seen == sorted(set(seen))  # four changes, four new versions
    s.record(make_point(1))  # not collecting: nothing changed
    assert s.version == seen[-1]


def test_invalid_points_are_refused_and_store_is_unchanged():
    s = collecting()
    s.record(make_point(0))
    bad = [
        DataPoint(0, math.nan, 0, 0, 0, 0, 0, 0, "manual", None),
        DataPoint(0, 0, math.inf, 0, 0, 0, 0, 0, "manual", None),
        DataPoint(0, 0, 0, 0, 0, 0, 0, 0, "", None),
        DataPoint(0, 0, 0, 0, True, 0, 0, 0, "manual", None),
        DataPoint(0, 0, 0, 0, 0, 0, 0, 0, "manual", math.nan),
    ]
    for p in bad:
        with pytest.raises(ValueError):
            s.record(p)
    assert len(s) == 1


def test_settings_are_validated():
    s = AnalyticsStore()
    for bad in (0, -1, math.nan, math.inf, True, "10"):
        with pytest.raises(ValueError):
            s.collection_rate = bad
    for bad in (0, -5, 1.5, True, 10**9):
        with pytest.raises(ValueError):
            s.max_data_points = bad


def test_shrinking_capacity_keeps_newest_and_growing_keeps_all():
    s = collecting(max_data_points=10)
    for i in range(25):
        s.record(make_point(i))
    s.max_data_points = 4
    assert [p.timestamp for p in s.points()] == [make_point(i).timestamp for i in range(21, 25)]
    s.max_data_points = 100
    s.record(make_point(25))
    assert [p.timestamp for p in s.points()] == [make_point(i).timestamp for i in range(21, 26)]


def test_concurrent_writers_lose_nothing():
    s = collecting(max_data_points=1_000_000)
    n_threads, per = 4, 5000

    def writer(t):
        for i in range(per):
            s.record(make_point(t * per + i, algorithm=f"algo{t}"))

    threads = [threading.Thread(target=writer, args=(t,)) for t in range(n_threads)]
    for th in threads:
        th.start()
    stats_during = [s.stats() for _ in range(20)]
    for th in threads:
        th.join()
    assert len(s) == n_threads * per
    assert all(st.sampleCount <= n_threads * per for st in stats_during)
    algos = s.algorithms()
    for t in range(n_threads):
        ts = [p.timestamp for p, a in zip(s.points(), algos, strict=False) if a == f"algo{t}"]
        assert ts == sorted(ts) and len(ts) == per  # each writer's points in its own order


def test_one_million_points_fit_under_100_bytes_each():
    s = collecting(max_data_points=1_000_000)
    p = make_point(1)
    for _ in range(1_000_000):
        s.record(p)
    assert len(s) == 1_000_000
    assert s.nbytes() / len(s) <= 100
    assert s.stats().sampleCount == 1_000_000
    assert np.all(s.column("x") == p.x)


@pytest.mark.parametrize("ring", [1, 7, 64])
@pytest.mark.parametrize("recorded", [0, 5, 7, 64, 150])
def test_the_newest_points_are_read_without_the_whole_ring(ring, recorded):
    """``column(last=k)`` and ``tail(k)`` (what the plots read) give the newest k points, oldest first,
    whether the ring has wrapped or not."""
    from ..support.points import make_point

    s = AnalyticsStore(max_data_points=ring)
    s.start_collection()
    for i in range(recorded):
        s.record(make_point(i, ("manual", "go_to_goal")[i % 2]))
    everything = s.points()
    for k in (1, 3, ring, ring + 5):
        want = everything[-k:] if everything else []
        assert s.column("x", last=k).tolist() == [p.x for p in want]
        cols, codes, names = s.tail(k)
        assert cols["timestamp"].tolist() == [p.timestamp for p in want]
        assert [names[c] for c in codes.tolist()] == [p.algorithm for p in want]
