"""Runs and samples from a robot's own topics (analytics/observe.py), on synthetic messages."""

import math

import numpy as np
import pytest

from arbiter_tui.analytics.observe import ObserveConfig, Observer
from arbiter_tui.analytics.runs import ABORTED, COMPLETED
from arbiter_tui.analytics.store import AnalyticsStore

S = 1_000_000_000  # ns
T0 = 1_800_000_000 * S


def observer(**kw) -> tuple[Observer, AnalyticsStore]:
    store = AnalyticsStore(max_data_points=100_000)
    store.start_collection()
    return Observer(store, ObserveConfig(**kw)), store


def straight_drive(obs: Observer, t0: int, x0: float, x1: float, v: float = 0.5, hz: int = 50) -> int:
    """Odometry along y = 0 from x0 to x1 at v, then two stopped messages; returns the last time."""
    n = round((x1 - x0) / v * hz)
    t = t0
    for k in range(n + 1):
        t = t0 + k * S // hz
        obs.on_odometry(t, x0 + (x1 - x0) * k / n, 0.0, 0.0, v if k < n else 0.0, 0.0)
    for k in range(1, 3):
        obs.on_odometry(t + k * S // hz, x1, 0.0, 0.0, 0.0, 0.0)
    return t + 2 * S // hz


def test_a_goal_starts_a_run_that_completes_where_the_robot_stops_at_it():
    obs, store = observer(label="nav2_rpp")
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_goal(T0 + S // 10, 2.0, 0.0)
    end = straight_drive(obs, T0 + S // 5, 0.0, 1.95)
    runs = store.runs()
    assert len(runs) == 1
    run = runs[0]
    assert (run.algorithm, run.mission, run.outcome) == ("nav2_rpp", "goal (+2.00, +0.00)", COMPLETED)
    assert run.final_error_m == pytest.approx(0.05)
    assert run.time_s == pytest.approx((end - (T0 + S // 10)) / 1e9, abs=0.1)  # to a 10 Hz sample
    assert run.tracking is not None and run.tracking.xte_max_m == pytest.approx(0.0, abs=1e-9)
    points = [p for p in store.points() if p.runId == run.id]
    assert all(p.distanceError == pytest.approx(2.0 - p.x) for p in points)
    # 10 Hz samples from 50 Hz odometry
    gaps = np.diff([p.timestamp for p in points])
    assert gaps.min() >= 99 and np.median(gaps) == pytest.approx(100, abs=1)


def test_a_replanned_path_to_the_same_goal_is_the_same_run_and_a_new_goal_aborts_it():
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    plan = [(0.1 * k, 0.0) for k in range(31)]  # to (3, 0)
    obs.on_plan(T0 + 1, plan)
    straight_drive(obs, T0 + S // 10, 0.0, 1.0)
    obs.on_plan(T0 + 3 * S, [(1.0, 0.0), (2.0, 0.0), (3.05, 0.0)])  # replanned: the end within tolerance
    assert len(store.runs()) == 1
    obs.on_goal(T0 + 4 * S, 0.0, 2.0)  # somewhere else: a new run
    obs.on_odometry(T0 + 5 * S, 1.0, 0.1, 0.0, 0.0, 0.0)
    first, second = store.runs()
    assert first.outcome == ABORTED and first.final_error_m == pytest.approx(2.0, abs=0.01)
    assert second.mission == "goal (+0.00, +2.00)" and store.active_run == second.id


def test_the_plan_is_the_reference_path_even_when_it_comes_before_any_odometry():
    obs, store = observer()
    detour = [(0.0, 0.0), (1.0, 1.0), (2.0, 0.0)]  # the robot drives the straight line: 0.5-0.7 m off
    obs.on_goal(T0, 2.0, 0.0)
    obs.on_plan(T0 + 1, detour)
    straight_drive(obs, T0 + S // 10, 0.0, 2.0)
    (run,) = store.runs()
    assert run.outcome == COMPLETED
    assert run.tracking.xte_max_m == pytest.approx(math.sqrt(0.5), abs=0.02)  # (1, 0) to the detour


def test_samples_carry_the_latest_command_and_a_stamped_commands_age():
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.3, 0.1)  # no command yet: the measured velocity
    obs.on_command(T0 + S // 5, 0.4, -0.2, stamp_ns=T0 + S // 5 - 3_500_000)
    obs.on_odometry(T0 + S // 4, 0.1, 0.0, 0.0, 0.4, -0.2)
    obs.on_command(T0 + S // 2, 0.5, 0.0)  # a plain Twist: no age
    obs.on_odometry(T0 + S, 0.3, 0.0, 0.0, 0.5, 0.0)
    first, second, third = store.points()
    assert (first.linearVel, first.angularVel, first.latencyMs) == (0.3, 0.1, None)
    assert (second.linearVel, second.angularVel, second.latencyMs) == (0.4, -0.2, 3.5)
    assert (third.linearVel, third.latencyMs) == (0.5, None)
    assert all(p.distanceError == 0.0 and p.runId is None for p in store.points())  # no goal yet


def test_the_data_ending_mid_run_leaves_it_aborted_and_bad_numbers_are_skipped():
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_goal(T0 + 1, 5.0, 0.0)
    obs.on_odometry(T0 + S, float("nan"), 0.0, 0.0, 0.0, 0.0)
    obs.on_command(T0 + S, float("inf"), 0.0)
    obs.on_plan(T0 + S, [])  # a failed plan (Nav2 publishes an empty path): nothing
    obs.on_odometry(T0 + 2 * S, 1.0, 0.0, 0.0, 0.5, 0.0)
    obs.finish()
    (run,) = store.runs()
    assert run.outcome == ABORTED and run.final_error_m == pytest.approx(4.0)
    assert len(store.points()) == 2


def test_a_rate_must_be_positive():
    with pytest.raises(ValueError):
        observer(rate_hz=0.0)


def test_the_same_goal_after_a_run_ended_is_a_new_run_and_a_replayed_one_during_it_is_not():
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_goal(T0 + 1, 1.0, 0.0)
    end = straight_drive(obs, T0 + S // 10, 0.0, 1.0)
    obs.on_odometry(end + S, 0.0, 0.0, 0.0, 0.0, 0.0)  # carried back to the start
    obs.on_goal(end + 2 * S, 1.0, 0.0)  # a second trial to the same point: a new run
    obs.on_goal(end + 3 * S, 1.0, 0.0)  # replayed while that run is in force: the same run
    straight_drive(obs, end + 4 * S, 0.0, 1.0)
    runs = store.runs()
    assert [r.outcome for r in runs] == [COMPLETED, COMPLETED] and len({r.id for r in runs}) == 2


def test_non_finite_plan_points_are_dropped_and_a_stamp_from_another_clock_gives_no_latency():
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_plan(T0 + 1, [(0.0, 0.0), (float("nan"), 1.0), (2.0, 0.0)])
    obs.on_command(T0 + S // 2, 0.3, 0.0, stamp_ns=120 * S)  # use_sim_time: 2 minutes after its start
    obs.on_odometry(T0 + S, 0.5, 0.0, 0.0, 0.3, 0.0)
    assert store.run(store.active_run).mission == "goal (+2.00, +0.00)"
    assert store.points()[-1].latencyMs is None and obs.foreign_stamps == 1
