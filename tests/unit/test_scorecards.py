"""The scorecards the field publishes (analytics/scorecards.py): Nav2's controller benchmark figures and
the BARN challenge score, per run and per controller, by hand; a missing input is a reason, never 0."""

import math
from dataclasses import replace

import numpy as np
import pytest

from arbiter_tui.analytics import scorecards as SC
from arbiter_tui.analytics.model import EMPTY_STATS
from arbiter_tui.analytics.runs import ABORTED, COMPLETED, RunSummary
from arbiter_tui.analytics.tracking import TrackingStats


def test_the_barn_score_clips_the_actual_time_between_two_and_eight_optimal_times():
    # reference 6 m: OT = 3 s
    assert SC.barn_score(True, 6.0, 10.0) == pytest.approx(3.0 / 10.0)
    assert SC.barn_score(True, 6.0, 4.0) == pytest.approx(3.0 / 6.0)  # faster than 2 OT counts as 2 OT
    assert SC.barn_score(True, 6.0, 100.0) == pytest.approx(3.0 / 24.0)  # slower than 8 OT: 8 OT
    assert SC.barn_score(False, 6.0, 4.0) == 0.0


def test_the_barn_clock_starts_once_the_robot_moved_a_tenth_of_a_metre():
    t = np.array([0.0, 100.0, 200.0, 300.0, 400.0])
    x = np.array([0.0, 0.05, 0.09, 0.1, 0.3])
    assert SC.barn_actual_s(t, x, np.zeros(5), 1300.0) == pytest.approx(1.0)
    assert SC.barn_actual_s(t, x * 0.3, np.zeros(5), 1300.0) is None  # it never moved 0.1 m


def test_a_scans_nearest_obstacle_and_a_runs_three_figures():
    ranges = np.array([np.inf, 0.05, 0.8, 5.0, np.nan, 0.3, 12.0])
    assert SC.nearest_obstacle(ranges, 0.12, 3.5) == 0.3  # 0.05 below range_min, 5 and 12 beyond range_max
    assert math.isnan(SC.nearest_obstacle(np.array([np.inf, 4.0]), 0.12, 3.5))
    o = SC.obstacles_of(np.array([0.5, np.nan, 0.3, 0.7]))
    assert (o.min_m.value, o.scans) == (0.3, 3)
    assert o.mean_min_m.value == pytest.approx(0.5)
    assert o.std_min_m.value == pytest.approx(math.sqrt((0.04 + 0.0 + 0.04) / 3))  # population std
    none = SC.obstacles_of(np.array([np.nan]))
    assert none.min_m.value is None and "saw anything in range" in none.min_m.why


def run(run_id: int, algorithm: str, success: float | None, time_s: float, path_m: float, jerk: float,
        ratio: float | None = 1.0) -> RunSummary:  # fmt: skip
    tracking = TrackingStats(10, 0.1, 0.1, 0.1, 0.1, time_s if success else None, ratio, 0.0, jerk, 2 * jerk,
                             success)  # fmt: skip
    outcome = COMPLETED if success else ABORTED
    stats = replace(EMPTY_STATS, totalPathLength=path_m)
    return RunSummary(run_id, algorithm, "goal (+1.00, +0.00)", 0.0, time_s * 1000, outcome, 0.1, stats, 10,
                      tracking=tracking)  # fmt: skip


def test_a_controllers_card_averages_over_its_successes_and_takes_the_smallest_obstacle():
    """As the benchmark's table: time, path and jerks over the runs that succeeded; the success rate over
    all; min obstacle the least of the runs', mean-min and std the mean of the runs'."""
    obstacles = [SC.obstacles_of(np.array(d)) for d in ([0.5, 0.7], [0.2, 0.4], [0.9])]
    runs = [
        run(1, "rpp", 1.0, 10.0, 5.0, 1.0),
        run(2, "rpp", 0.0, 30.0, 9.0, 7.0),
        run(3, "rpp", 1.0, 20.0, 6.0, 3.0),
    ]
    cards = [SC.run_card(r, None, o) for r, o in zip(runs, obstacles, strict=True)]
    assert cards[1].time_to_goal_s.value is None and cards[1].time_to_goal_s.why == "the run did not succeed"
    (c,) = SC.controller_cards(cards)
    assert (c.runs, c.successes, c.success_rate.value) == (3, 2, pytest.approx(2 / 3))
    assert c.time_to_goal_s.value == 15.0 and c.path_length_m.value == 5.5
    assert (c.linear_jerk.value, c.angular_jerk.value) == (2.0, 4.0)
    assert c.obstacles.min_m.value == 0.2
    assert c.obstacles.mean_min_m.value == pytest.approx((0.6 + 0.3 + 0.9) / 3)
    assert c.obstacles.std_min_m.value == pytest.approx((0.1 + 0.1 + 0.0) / 3)


def test_missing_inputs_are_reasons_never_zero():
    no_scan = SC.no_obstacles("no sensor_msgs/LaserScan on /scan in the recording")
    failed = SC.run_card(run(1, "rpp", 0.0, 30.0, 9.0, 7.0), None, no_scan)
    assert failed.barn.value == 0.0  # a failure scores 0 by the formula: that is a figure
    partial = SC.run_card(run(2, "rpp", 1.0, 10.0, 5.0, 1.0), None, no_scan)
    assert partial.barn.value is None and "part of the run" in partial.barn.why
    unmoved = SC.run_card(run(3, "rpp", 1.0, 10.0, 0.0, 1.0, ratio=0.0), None, no_scan)
    assert unmoved.barn.value is None and "reference path length" in unmoved.barn.why
    assert partial.obstacles.min_m.text() == "— (no sensor_msgs/LaserScan on /scan in the recording)"
    (c,) = SC.controller_cards([failed])
    assert c.time_to_goal_s.value is None and c.time_to_goal_s.why == "no run succeeded"
    assert c.obstacles.min_m.as_dict() == {
        "value": None,
        "why": "no sensor_msgs/LaserScan on /scan in the recording",
    }
    manual = RunSummary(4, "manual", "", 0.0, 1000.0, "ended", None, EMPTY_STATS, 1)
    assert SC.controller_cards([SC.run_card(manual, None, no_scan)]) == []
