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


# -- the reference a controller follows (README, "Grade any controller") ---------------------------------


def drive_x(obs: Observer, t0: int, x0: float, x1: float, v: float = 0.5, final_zero: bool = True) -> int:
    """Along y = 0 from x0 to x1 at v: odometry at 50 Hz and the controller's command at 20 Hz (zero once
    there, unless not ``final_zero``); then 0.2 s standing. Returns the last time."""
    n = round(abs(x1 - x0) / v * 50)
    t = t0
    for k in range(n + 1):
        t = t0 + k * S // 50
        if k % 5 in (0, 2) and (k < n or final_zero):
            obs.on_command(t - MS, v if k < n else 0.0, 0.0)
        obs.on_odometry(t, x0 + (x1 - x0) * k / n, 0.0, 0.0, v if k < n else 0.0, 0.0)
    for k in range(1, 11):
        obs.on_odometry(t + k * S // 50, x1, 0.0, 0.0, 0.0, 0.0)
    return t + 10 * S // 50


MS = S // 1000  # a command comes 1 ms before the odometry (the ms timestamps tell them apart)


def run_points(store: AnalyticsStore, run_id: int) -> list:
    return [p for p in store.points() if p.runId == run_id]


def line(y: float, x0: float, x1: float) -> list[tuple[float, float]]:
    return [(x0 + (x1 - x0) * k / 10, y) for k in range(11)]


def test_each_sample_is_measured_against_the_latest_plan_and_the_path_ratio_against_the_first():
    """A run started by a plan alone (NavigateToPose, no goal_pose), replanned half-way: the samples
    before the replan are 0.10 m from the first plan, those after it 0.03 m from the second. Measured
    against the first plan only they would all be 0.10; against the latest only, all 0.03 (today's main
    took the first replan for every sample: 0.03)."""
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_plan(T0 + 1, line(0.10, -1.0, 4.0))  # 5 m long, ends at the goal (4, 0.1)
    replan = T0 + S // 10 + 4 * S + S // 200  # the robot is at x = 2.0
    t = T0 + S // 10
    for k in range(0, 401):
        t = T0 + S // 10 + k * S // 50
        if t >= replan and t - S // 50 < replan:
            obs.on_plan(replan, line(-0.03, 1.5, 4.0))  # 2.5 m long, ends 0.13 m from the goal: a replan
        if k % 5 in (0, 2):
            obs.on_command(t - 1, 0.5 if k < 400 else 0.0, 0.0)
        obs.on_odometry(t, 4.0 * k / 400, 0.0, 0.0, 0.5 if k < 400 else 0.0, 0.0)
    obs.on_odometry(t + S // 10, 4.0, 0.0, 0.0, 0.0, 0.0)
    (run,) = store.runs()
    assert run.outcome == COMPLETED
    points = run_points(store, run.id)
    before = sum(1 for p in points if p.timestamp * 1e6 < replan)
    after = len(points) - before
    assert before > 30 and after > 30
    expected = (before * 0.10 + after * 0.03) / len(points)
    assert run.tracking.xte_mean_m == pytest.approx(expected, abs=1e-12)
    assert run.tracking.xte_max_m == pytest.approx(0.10, abs=1e-12)
    assert run.tracking.path_ratio == pytest.approx(run.stats.totalPathLength / 5.0, abs=1e-12)


def test_a_goal_is_measured_against_the_straight_line_until_its_plan_then_the_plan_and_a_later_goal_too():
    """Two runs in a row: the first started by a plan (and replanned), the second by goal_pose, its plan
    coming a second later. Each run's samples before its plan are against the straight line, after it
    against the plan; path ratio against the plan (today's main kept the second run's straight line)."""
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_plan(T0 + 1, line(0.0, 0.0, 2.0))
    obs.on_plan(T0 + S // 2, line(0.0, 0.0, 2.0))  # replanned: the same path
    end = drive_x(obs, T0 + S // 10, 0.0, 2.0)
    (first,) = store.runs()
    assert first.outcome == COMPLETED and first.tracking.xte_max_m == pytest.approx(0.0, abs=1e-12)
    obs.on_goal(end + S, 6.0, 0.1)  # from (2, 0): the straight line to (6, 0.1)
    for k in range(10):  # a second standing at the start while the planner works
        obs.on_odometry(end + S + k * S // 10 + 1, 2.0, 0.0, 0.0, 0.0, 0.0)
    plan_t = end + 2 * S
    obs.on_plan(plan_t, line(0.1, 1.0, 6.0))  # 5 m, 0.1 m beside the robot's track
    drive_x(obs, plan_t + S // 10, 2.0, 6.0)
    second = store.runs()[1]
    points = run_points(store, second.id)
    standing = [p for p in points if p.timestamp * 1e6 < plan_t]
    moving = [p for p in points if p.timestamp * 1e6 > plan_t]
    assert len(standing) >= 9 and len(moving) > 70
    assert second.tracking.xte_mean_m == pytest.approx(0.1 * len(moving) / len(points), abs=1e-12)
    assert second.tracking.path_ratio == pytest.approx(second.stats.totalPathLength / 5.0, abs=1e-12)


def test_a_goal_whose_plan_never_comes_keeps_the_straight_line_and_an_empty_plan_changes_nothing():
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_goal(T0 + 1, 2.0, 0.1)  # the straight line from (0, 0): the robot drives y = 0
    t = T0 + S // 10
    for k in range(0, 201):
        t = T0 + S // 10 + k * S // 50
        if k == 100:
            obs.on_plan(t - 1, [])  # planning failed: Nav2 publishes an empty path
        if k % 5 in (0, 2):
            obs.on_command(t - 1, 0.5 if k < 200 else 0.0, 0.0)
        obs.on_odometry(t, 2.0 * k / 200, 0.0, 0.0, 0.5 if k < 200 else 0.0, 0.0)
    obs.on_odometry(t + S // 10, 2.0, 0.0, 0.0, 0.0, 0.0)
    (run,) = store.runs()
    points = run_points(store, run.id)
    # distance from (x, 0) to the line through (0, 0) and (2, 0.1)
    expected = [p.x * 0.1 / math.hypot(2.0, 0.1) for p in points]
    assert run.outcome == COMPLETED and run.tracking.samples == len(points)
    assert run.tracking.xte_mean_m == pytest.approx(sum(expected) / len(expected), abs=1e-12)
    assert run.tracking.path_ratio == pytest.approx(run.stats.totalPathLength / math.hypot(2.0, 0.1))


def test_a_goal_with_replans_before_any_odometry_starts_on_the_latest_and_rates_against_the_first():
    obs, store = observer()
    obs.on_goal(T0, 2.0, 0.0)
    obs.on_plan(T0 + 1, line(0.1, -2.0, 2.0))  # the first plan: 4 m
    obs.on_plan(T0 + 2, line(0.05, 0.0, 2.0))  # replanned before the first odometry
    drive_x(obs, T0 + S // 10, 0.0, 2.0)
    (run,) = store.runs()
    assert run.tracking.xte_mean_m == pytest.approx(0.05, abs=1e-12)
    assert run.tracking.path_ratio == pytest.approx(run.stats.totalPathLength / 4.0, abs=1e-12)


# -- when an observed run ends -------------------------------------------------------------------------


def test_a_controller_that_stops_short_ends_its_run_where_it_stopped_not_at_the_next_plan():
    """Zero commands for stalled_s, 1 m short of the goal: the run ends as aborted at the first zero
    command; the standing samples after it belong to no run (today's main kept it running, its error
    growing with every standing sample, until the data ended)."""
    obs, store = observer(stalled_s=2.0)
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_plan(T0 + 1, line(0.1, 0.0, 3.0))
    end = drive_x(obs, T0 + S // 10, 0.0, 2.0)  # its last command (zero) at 2.0 m
    stop_ns = T0 + S // 10 + 200 * S // 50 - MS
    for k in range(1, 60):  # six seconds standing, the controller sending zero
        obs.on_command(end + k * S // 10 - MS, 0.0, 0.0)
        obs.on_odometry(end + k * S // 10, 2.0, 0.0, 0.0, 0.0, 0.0)
    obs.finish()
    (run,) = store.runs()
    assert run.outcome == ABORTED and run.final_error_m == pytest.approx(math.hypot(1.0, 0.1))
    assert run.end_ms == pytest.approx(stop_ns / 1e6)
    assert all(p.timestamp <= stop_ns / 1e6 for p in run_points(store, run.id))
    assert run.stats.sampleCount == len(run_points(store, run.id))
    after = [p for p in store.points() if p.timestamp > stop_ns / 1e6]
    # the stalled window's samples (the run's until it ended, then dropped from it), and one of the robot
    # standing after the run, not one each 0.1 s (runs.IdleSamples)
    assert after and all(p.runId is None for p in after)
    assert len(after) <= 2.0 * 10 + 2


def test_a_robot_standing_outside_any_run_gives_one_sample_until_it_moves():
    """The console's rule (issue 54): observe mode, no goal and no run, the robot at v = 0 for 5 s adds
    one sample, not 50; a command or motion samples again at the rate, and standing again one more."""
    obs, store = observer()
    for k in range(50):  # 5 s standing, nothing commanded
        obs.on_odometry(T0 + k * S // 10, 1.0, 2.0, 0.5, 0.0, 0.001)
    assert len(store) == 1 and store.points()[0].runId is None
    obs.on_command(T0 + 5 * S, 0.0, 0.0)  # a zero command is no command
    for k in range(50, 60):
        obs.on_odometry(T0 + k * S // 10, 1.0, 2.0, 0.5, 0.0, 0.0)
    assert len(store) == 1
    obs.on_command(T0 + 6 * S, 0.3, 0.0)  # a teleop node drives it, outside any run
    for k in range(60, 70):
        obs.on_odometry(T0 + k * S // 10, 1.0 + 0.03 * (k - 59), 2.0, 0.5, 0.3, 0.0)
    assert len(store) == 11
    obs.on_command(T0 + 7 * S, 0.0, 0.0)
    for k in range(70, 90):  # stopped again: one sample where it stopped
        obs.on_odometry(T0 + k * S // 10, 1.3, 2.0, 0.5, 0.0, 0.0)
    assert len(store) == 12


def test_a_controller_gone_silent_ends_at_its_last_command_and_a_short_pause_ends_nothing():
    obs, store = observer(stalled_s=2.0)
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_goal(T0 + 1, 4.0, 0.0)
    t = drive_x(obs, T0 + S // 10, 0.0, 1.0)
    for k in range(1, 15):  # a 1.4 s pause: zero commands, shorter than stalled_s
        obs.on_command(t + k * S // 10 - 1, 0.0, 0.0)
        obs.on_odometry(t + k * S // 10, 1.0, 0.0, 0.0, 0.0, 0.0)
    t1 = t + 15 * S // 10
    t = drive_x(obs, t1, 1.0, 2.0, final_zero=False)  # the controller dies while driving
    assert store.active_run is not None
    last_cmd = t1 + 97 * S // 50 - MS  # its last command, at the 97th of 100 odometry steps
    for k in range(1, 40):  # no command at all, odometry still coming
        obs.on_odometry(t + k * S // 10, 2.0, 0.0, 0.0, 0.0, 0.0)
    (run,) = store.runs()
    assert run.outcome == ABORTED and store.active_run is None
    assert run.end_ms == pytest.approx(last_cmd / 1e6)


def test_a_run_whose_controller_never_moves_ends_stalled_s_after_it_began():
    obs, store = observer(stalled_s=3.0)
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_goal(T0 + 1, 4.0, 0.0)
    for k in range(1, 50):
        obs.on_odometry(T0 + k * S // 10, 0.0, 0.0, 0.0, 0.0, 0.0)
    (run,) = store.runs()
    assert run.outcome == ABORTED and run.time_s == pytest.approx(3.0, abs=0.11)


def nav2_status(obs: Observer, t: int, *goals: tuple[str, int]) -> None:
    obs.on_goal_status(t, list(goals))


def test_the_actions_status_ends_the_run_with_its_outcome_and_holds_it_through_a_long_recovery():
    """With Nav2's navigate_to_pose status: a 12 s wait (a recovery: no commands) does not end the run
    (stalled_s is 10 s); SUCCEEDED ends it completed 0.2 m from the goal (Nav2's goal checker allows
    0.25 m, ours 0.15 m)."""
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    nav2_status(obs, T0 + 1, ("g1", 1))
    nav2_status(obs, T0 + 2, ("g1", 2))
    obs.on_plan(T0 + 3, line(0.0, 0.0, 3.2))
    t = drive_x(obs, T0 + S // 10, 0.0, 1.0)
    for k in range(1, 121):  # 12 s: the controller silent, the robot standing
        obs.on_odometry(t + k * S // 10, 1.0, 0.0, 0.0, 0.0, 0.0)
    assert store.active_run is not None
    t = drive_x(obs, t + 121 * S // 10, 1.0, 3.0)
    assert store.active_run is not None  # 0.2 m short: not within our tolerance
    nav2_status(obs, t + S // 10, ("g1", 4))
    (run,) = store.runs()
    assert run.outcome == COMPLETED and run.final_error_m == pytest.approx(0.2)
    assert run.end_ms == pytest.approx((t + S // 10) / 1e6)


@pytest.mark.parametrize("status", [5, 6])  # CANCELED, ABORTED
def test_a_canceled_or_aborted_action_goal_aborts_the_run_and_a_resent_goal_to_the_same_point_is_a_new_run(
    status: int,
):
    obs, store = observer()
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    nav2_status(obs, T0 + 1, ("g1", 2))
    obs.on_plan(T0 + 2, line(0.0, 0.0, 3.0))
    t = drive_x(obs, T0 + S // 10, 0.0, 1.0)
    nav2_status(obs, t + 1, ("g1", status))
    first = store.runs()[0]
    assert first.outcome == ABORTED and first.end_ms == pytest.approx((t + 1) / 1e6)
    obs.on_plan(t + S // 2, line(0.0, 1.0, 3.0))  # a late replan of the ended goal: no run
    obs.on_odometry(t + S, 1.0, 0.0, 0.0, 0.0, 0.0)
    assert store.active_run is None
    nav2_status(obs, t + 2 * S, ("g1", status), ("g2", 2))  # the same goal sent again
    obs.on_plan(t + 2 * S + 1, line(0.0, 1.0, 3.0))
    drive_x(obs, t + 2 * S + S // 10, 1.0, 3.0)
    runs = store.runs()
    assert [r.outcome for r in runs] == [ABORTED, COMPLETED] and runs[1].mission == first.mission


def test_without_any_command_the_odometry_says_when_the_robot_stopped():
    """A recording with no cmd_vel (odometry and plans only): the run goes on while the robot moves, and
    ends where it stood still for stalled_s short of the goal."""
    obs, store = observer(stalled_s=2.0)
    obs.on_odometry(T0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_plan(T0 + 1, line(0.0, 0.0, 4.0))
    t = T0
    for k in range(1, 151):  # 3 s driving at 0.5 m/s (no command recorded), then 3 s standing at 1.5 m
        t = T0 + k * S // 50
        obs.on_odometry(t, 0.01 * k, 0.0, 0.0, 0.5, 0.0)
    assert store.active_run is not None  # 3 s of motion: no stall
    for k in range(1, 151):
        obs.on_odometry(t + k * S // 50, 1.5, 0.0, 0.0, 0.0, 0.0)
    (run,) = store.runs()
    assert run.outcome == ABORTED and run.end_ms == pytest.approx((t + S // 50) / 1e6)  # its first standstill
