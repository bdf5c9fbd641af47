"""Path-tracking metrics (cross-track error, time, path ratio, smoothness), trials with 95 % intervals,
and what latency does to each controller on the square."""

import math

import numpy as np
import pytest

from arbiter_core.linkmodel import LinkModel
from arbiter_core.stats import mean_ci95, t975
from arbiter_tui.analytics import tracking as T
from arbiter_tui.analytics.exports import read_mcap, runs_from, to_json, to_mcap
from arbiter_tui.analytics.runs import COMPLETED
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.commands.compare import Sweep, run_sweep
from arbiter_tui.session import trials as TR
from arbiter_tui.session.compare import AUTONOMOUS, run_one


def test_cross_track_is_the_distance_to_the_nearest_segment():
    path = T.reference_path((0.0, 0.0), [(2.0, 0.0), (2.0, 2.0)])
    x = np.array([1.0, 1.0, 3.0, 2.5, -1.0, 2.0])
    y = np.array([0.0, 0.3, 1.0, -0.5, 0.0, 3.0])
    # on the path; beside the first leg; beside the second; off the corner (to the corner point);
    # behind the start; past the end
    expected = [0.0, 0.3, 1.0, math.hypot(0.5, 0.5), 1.0, 1.0]
    assert T.cross_track(x, y, path) == pytest.approx(expected)
    assert T.path_length(path) == 4.0
    # a goal run from where the robot stood: one segment; a zero-length path is a point
    assert T.cross_track(np.array([1.0]), np.array([1.0]), T.reference_path((0, 0), [(2, 0)])) == [1.0]
    assert T.cross_track(np.array([3.0]), np.array([4.0]), T.reference_path((0, 0), [])) == [5.0]


def test_tracking_stats_formulas():
    path = T.reference_path((0.0, 0.0), [(10.0, 0.0)])
    e = np.array([0.0, 0.1, 0.2, 0.3, 0.4])
    t = np.array([0.0, 0.1, 0.2, 0.3, 0.4])
    w = np.array([0.0, 0.5, 0.5, 0.0, 0.0])  # |dw/dt|: 5, 0, 5, 0 -> mean 2.5
    s = T.tracking_stats(t, np.arange(5.0), e, np.zeros(5), w, path, travelled=5.0, completed_time_s=12.0)
    assert s.samples == 5 and s.xte_mean_m == pytest.approx(0.2) and s.xte_max_m == pytest.approx(0.4)
    assert s.xte_rms_m == pytest.approx(math.sqrt((0.01 + 0.04 + 0.09 + 0.16) / 5))
    assert s.xte_p95_m == pytest.approx(0.4)  # the seed's rule: sorted[floor(0.95 * 5)] = sorted[4]
    assert s.path_ratio == pytest.approx(0.5) and s.time_to_complete_s == 12.0
    assert s.mean_abs_dw_dt == pytest.approx(2.5)
    assert T.TrackingStats.from_dict(s.as_dict()) == T.TrackingStats.from_dict(s.as_dict())
    with pytest.raises(ValueError, match=r"tracking\.xte_mean_m"):
        T.TrackingStats.from_dict({**s.as_dict(), "xte_mean_m": float("nan")})
    with pytest.raises(ValueError, match="samples"):
        T.TrackingStats.from_dict({**s.as_dict(), "samples": -1})


def test_integrated_jerk_is_the_squared_second_derivative_of_the_command_integrated():
    t = np.linspace(0.0, 1.0, 11)
    assert T.integrated_jerk(t, np.full(11, 0.4)) == 0.0  # a constant command
    assert T.integrated_jerk(t, 0.3 * t) == pytest.approx(0.0, abs=1e-9)  # a constant acceleration
    # u = t^2: jerk 2 everywhere, over the midpoints' span 0.05..0.95 -> 4 * 0.9
    assert T.integrated_jerk(t, t**2) == pytest.approx(3.6)
    # u = t^3: jerk 6t at the second differences' centres -> sum 36 t_k^2 * 0.1 over t = 0.1..0.9
    assert T.integrated_jerk(t, t**3) == pytest.approx(sum(36 * (k / 10) ** 2 * 0.1 for k in range(1, 10)))
    # a sample at a time already seen is skipped, not divided by zero; too few samples: 0
    doubled = np.concatenate((t[:5], t[4:]))
    assert T.integrated_jerk(doubled, doubled**2) == pytest.approx(3.6)
    assert T.integrated_jerk(t[:2], t[:2]) == 0.0
    # a sharper stop costs more: the same 0.5 m/s shed over 0.1 s rather than 1 s
    slow = np.clip(0.5 - 0.5 * (t - 0.0), 0.0, None)
    fine = np.linspace(0.0, 1.0, 101)
    sharp = np.where(fine < 0.5, 0.5, np.clip(0.5 - 5.0 * (fine - 0.5), 0.0, None))
    gentle = np.where(fine < 0.5, 0.5, np.clip(0.5 - 1.0 * (fine - 0.5), 0.0, None))
    assert T.integrated_jerk(fine, sharp) > 10 * T.integrated_jerk(fine, gentle) > 0
    assert T.integrated_jerk(t, slow) == pytest.approx(0.0, abs=1e-9)


def test_success_is_completion_within_the_time_limit():
    path = T.reference_path((0.0, 0.0), [(10.0, 0.0)])  # 10 m: limit 10 s + 100 s
    assert T.time_limit_s(10.0) == 110.0
    z = np.zeros(3)
    t = np.array([0.0, 1.0, 2.0])

    def run(done: float | None) -> T.TrackingStats:
        return T.tracking_stats(t, t, z, z + 0.5, z, path, 2.0, done)

    assert run(12.0).success == 1.0 and run(110.0).success == 1.0
    assert run(110.5).success == 0.0 and run(None).success == 0.0
    rows = [(np.zeros(3), run(d), 3) for d in (12.0, None, 50.0, 200.0)]
    assert T.pooled(rows).success == 0.5  # the success rate
    assert run(12.0).linear_jerk == 0.0 and run(12.0).angular_jerk == 0.0


def test_tracking_written_before_the_jerks_and_success_existed_still_reads():
    old = {"samples": 3, "xte_mean_m": 0.1, "xte_rms_m": 0.1, "xte_p95_m": 0.2, "xte_max_m": 0.2,
           "time_to_complete_s": None, "path_ratio": 1.1, "mean_abs_dw_dt": 0.5}  # fmt: skip
    s = T.TrackingStats.from_dict(old)
    assert (s.linear_jerk, s.angular_jerk, s.success) == (None, None, None) and s.path_ratio == 1.1
    with pytest.raises(ValueError, match=r"tracking\.success"):
        T.TrackingStats.from_dict({**old, "success": 2.0})
    with pytest.raises(ValueError, match=r"tracking\.linear_jerk"):
        T.TrackingStats.from_dict({**old, "linear_jerk": "big"})


def test_a_run_in_the_store_is_measured_against_its_path_and_exports_keep_it():
    store = AnalyticsStore(max_data_points=1000)
    store.start_collection()
    result = run_one("pure_pursuit", "square")
    run = store.begin_run(
        "pure_pursuit", "square", 0.0, T.reference_path((0.0, 0.0), [(2, 0), (2, 2), (0, 2), (0, 0)])
    )
    from dataclasses import replace

    for p in result.points:
        store.record(replace(p, runId=run))
    store.end_run(COMPLETED, result.points[-1].timestamp + 50, result.final_error_m)
    (summary,) = store.runs()
    # perfect link: the console's odometry is the true pose, so the store says what compare says
    assert summary.tracking.xte_mean_m == pytest.approx(result.tracking.xte_mean_m, abs=1e-9)
    assert summary.tracking.xte_max_m == pytest.approx(result.tracking.xte_max_m, abs=1e-9)
    # the jerks from the samples' own times, the same in both (and not nothing: the square has corners)
    assert result.tracking.angular_jerk > 0 and result.tracking.linear_jerk > 0
    assert summary.tracking.angular_jerk == pytest.approx(result.tracking.angular_jerk, rel=1e-6)
    assert summary.tracking.linear_jerk == pytest.approx(result.tracking.linear_jerk, rel=1e-6)
    assert summary.tracking.success == result.tracking.success == 1.0
    (row,) = store.runs_by_algorithm()
    assert row.tracking.xte_mean_m == pytest.approx(summary.tracking.xte_mean_m)
    import json

    doc = json.loads(to_json(store.points(), None, store.runs(), store.runs_by_algorithm()))
    (back,) = runs_from(doc["runs"], {})
    assert back.tracking == T.TrackingStats.from_dict(summary.tracking.as_dict())
    export = read_mcap(to_mcap(store.points(), None, store.runs(), store.runs_by_algorithm()))
    assert export.runs[0].tracking.xte_mean_m == pytest.approx(summary.tracking.xte_mean_m, abs=1e-6)
    assert export.algorithms[0].tracking.path_ratio == pytest.approx(row.tracking.path_ratio, abs=1e-6)
    assert export.runs[0].tracking.angular_jerk == pytest.approx(summary.tracking.angular_jerk, rel=1e-6)
    assert export.runs[0].tracking.success == 1.0


def test_a_manual_run_has_no_tracking_metrics():
    store = AnalyticsStore()
    store.start_collection()
    store.begin_run("manual", "", 0.0)
    assert store.runs() == () or store.runs()[0].tracking is None


def test_mean_ci95_uses_students_t():
    assert t975(1) == 12.706 and t975(9) == 2.262 and t975(60) == pytest.approx(2.0, abs=0.005)
    assert mean_ci95([1.0, 2.0, 3.0]) == pytest.approx((2.0, 4.303 * 1.0 / math.sqrt(3)))
    assert mean_ci95([5.0]) == (5.0, 0.0) and mean_ci95([]) == (0.0, 0.0)
    with pytest.raises(ValueError):
        t975(0)


def _summary(algorithm: str, mission: str, xte: list[float]):
    from dataclasses import replace

    base = run_one(algorithm, mission)
    runs = [replace(base, tracking=replace(base.tracking, xte_mean_m=v)) for v in xte]
    return TR.summarize(runs)


def test_no_clear_winner_when_the_intervals_overlap():
    a = _summary("stanley", "corner", [0.010, 0.012, 0.014])
    b = _summary("pure_pursuit", "corner", [0.013, 0.015, 0.017])
    (v,) = TR.verdicts([a, b])
    assert v.best is None and v.overlapping == ("pure_pursuit",) and v.reason.startswith("no clear winner")
    c = _summary("pure_pursuit", "corner", [0.030, 0.031, 0.032])
    (v,) = TR.verdicts([a, c])
    assert v.best == "stanley" and v.overlapping == () and "apart from every other" in v.reason


def test_each_controllers_tracking_on_the_square_at_300_ms_against_0_ms_over_10_seeds():
    """The issue expects every controller to track worse at 300 ms. Measured (10 trials, 20 ms jitter):
    the path trackers do; go_to_goal and kanayama track the square's corners *better* at 300 ms — the
    late command keeps them turning in place longer before they speed up, so they swing wide of the
    corner less (README, "Is my link good enough?") — and all five take longer to complete it. At
    500 ms kanayama tracks worse too; go_to_goal still swings wide less than at 0 ms."""
    cells = run_sweep(
        Sweep(
            ["square"],
            list(AUTONOMOUS),
            0.5,
            1.0,
            [LinkModel(0.0, 0.02), LinkModel(0.3, 0.02), LinkModel(0.5, 0.02)],
            seed=0,
            trials=10,
        )
    )
    at = {ms: {s.algorithm: s for s in c.summaries} for ms, c in zip((0, 300, 500), cells, strict=True)}
    for name in AUTONOMOUS:
        assert at[300][name].completions == 10
        assert at[300][name].figures["time_s"].low > at[0][name].figures["time_s"].high
    for name in ("pure_pursuit", "stanley", "regulated_pure_pursuit"):
        assert at[300][name].figures["xte_mean_m"].low > at[0][name].figures["xte_mean_m"].high, name
    for name in ("go_to_goal", "kanayama"):
        assert at[300][name].figures["xte_mean_m"].high < at[0][name].figures["xte_mean_m"].low, name
    assert at[500]["kanayama"].figures["xte_mean_m"].low > at[0]["kanayama"].figures["xte_mean_m"].high


def _brute_cross_track(x: np.ndarray, y: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Every sample against every segment (what cross_track computed before it was indexed)."""
    px, py = np.asarray(x, dtype=np.float64)[:, None], np.asarray(y, dtype=np.float64)[:, None]
    if len(path) == 1:
        return np.hypot(px[:, 0] - path[0, 0], py[:, 0] - path[0, 1])
    a, d = path[:-1], path[1:] - path[:-1]
    seg2 = (d * d).sum(axis=1)
    u = np.clip(((px - a[:, 0]) * d[:, 0] + (py - a[:, 1]) * d[:, 1]) / np.where(seg2 > 0, seg2, 1.0), 0, 1)
    u = np.where(seg2 > 0, u, 0.0)
    ex, ey = px - (a[:, 0] + u * d[:, 0]), py - (a[:, 1] + u * d[:, 1])
    return np.sqrt((ex * ex + ey * ey).min(axis=1))


def test_the_indexed_cross_track_is_the_brute_force_minimum_on_paths_that_loop_and_cross():
    from arbiter_core.controllers import MISSIONS

    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 6 * math.pi, 900)
    circle = np.stack((np.cos(t[:300] / 3), np.sin(t[:300] / 3)), axis=1)
    paths = [
        *(T.reference_path((0.0, 0.0), MISSIONS[m]) for m in MISSIONS),
        np.stack((2 * np.sin(t), np.sin(2 * t)), axis=1),  # a figure eight three times over itself
        np.cumsum(rng.normal(size=(2000, 2)) * 0.05, axis=0),  # a random walk, crossing itself
        rng.normal(size=(300, 2)) * 4.0,  # segments in every direction
        circle,  # a sample at the centre is as far from every segment: nothing can be pruned
        np.repeat([[1.0, 1.0], [2.0, 1.0]], 20, axis=0),  # repeated poses: segments of no length
    ]
    for path in paths:
        x, y = rng.normal(size=500) * 3, rng.normal(size=500) * 3
        x[:3], y[:3] = 0.0, 0.0
        x[3:6], y[3:6] = path[:3, 0], path[:3, 1]  # on the path's vertices
        assert np.array_equal(T.cross_track(x, y, path), _brute_cross_track(x, y, path))


def test_cross_track_memory_grows_with_the_path_not_with_samples_times_poses():
    """4,000 poses and 6,000 samples: a samples x segments matrix is 192 MB an array (several at once)."""
    import tracemalloc

    k, n = 4000, 6000
    s = np.arange(k) * 0.05
    path = np.stack((s, np.sin(s / 2)), axis=1)
    x = np.linspace(0.0, s[-1], n)
    y = np.sin(x / 2) + 0.1 * np.cos(x)
    tracemalloc.start()
    try:
        e = T.cross_track(x, y, path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 16e6, f"{peak / 1e6:.0f} MB"
    every = slice(None, None, 50)
    assert np.array_equal(e[every], _brute_cross_track(x[every], y[every], path))
