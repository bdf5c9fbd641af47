"""Runs: golden per-run statistics (hand-computed), the ring dropping a run's samples, stationary samples,
the ranking rule, and where the control loop begins and ends runs."""

import math

import pytest

from arbiter_tui.analytics.ranking import RULE, best_in, ranked
from arbiter_tui.analytics.runs import (
    ABORTED,
    COMPLETED,
    ENDED,
    OVERRIDDEN,
    AlgorithmSummary,
    RunLog,
    best_in_columns,
)
from arbiter_tui.analytics.store import AnalyticsStore, DataPoint
from arbiter_tui.control.loop import ControlLoop
from arbiter_tui.control.teleop import Teleop
from arbiter_tui.link.sim import SimLink

# (x, y, v, w, e_d, e_th): path 3-4-5 then 4 back down = 9 m
GOLDEN = [(0, 0, 0.5, 0.0, 1.0, 0.1), (3, 4, -0.5, 0.2, 2.0, -0.1), (3, 4, 0.5, -0.2, 3.0, 0.2),
          (3, 0, 0.5, 0.0, 4.0, -0.2)]  # fmt: skip


def point(t: float, x: float, y: float, v: float, w: float, e_d: float, e_th: float, run: int | None,
          algorithm: str = "go_to_goal") -> DataPoint:  # fmt: skip
    return DataPoint(t, x, y, 0.0, v, w, e_d, e_th, algorithm, None, run)


def check_golden(stats) -> None:
    assert stats.sampleCount == 4
    assert stats.avgLinearVel == pytest.approx(0.5)
    assert stats.avgAngularVel == pytest.approx(0.1)
    assert stats.maxLinearVel == pytest.approx(0.5)
    assert stats.avgDistanceError == pytest.approx(2.5)
    assert stats.avgHeadingError == pytest.approx(0.15)
    assert stats.stdDevError == pytest.approx(math.sqrt(1.25))
    assert stats.p95Error == 4.0  # sorted[floor(4 * 0.95)] = sorted[3]
    assert stats.totalPathLength == pytest.approx(9.0)


def test_a_run_keeps_all_its_samples_after_the_ring_dropped_some():
    store = AnalyticsStore(max_data_points=3)
    store.start_collection()
    store.record(point(0, 9, 9, 0, 0, 7.0, 0, None))  # standing still before the run: in no run
    run = store.begin_run("go_to_goal", "square", 100.0)
    for i, row in enumerate(GOLDEN):
        store.record(point(100 + 100 * i, *row, run))
    store.end_run(COMPLETED, 500.0, final_error_m=0.12)
    (summary,) = store.runs()
    check_golden(summary.stats)
    assert (summary.in_ring, summary.dropped) == (3, 1)  # the ring holds 3 of its 4
    assert summary.completed and summary.time_s == pytest.approx(0.4) and summary.final_error_m == 0.12
    # the seed's whole-buffer stats cover exactly what the ring holds
    assert store.stats().sampleCount == 3 and store.stats().avgDistanceError == pytest.approx(3.0)


def test_shrinking_the_ring_counts_the_dropped_samples_of_each_run():
    store = AnalyticsStore(max_data_points=100)
    store.start_collection()
    a = store.begin_run("go_to_goal", "square", 0.0)
    for i, row in enumerate(GOLDEN):
        store.record(point(i, *row, a))
    b = store.begin_run("pure_pursuit", "square", 10.0)  # ends run a as aborted
    for i, row in enumerate(GOLDEN):
        store.record(point(10 + i, *row, b))
    store.max_data_points = 2
    first, second = store.runs()
    assert first.outcome == ABORTED and (first.in_ring, first.dropped) == (0, 4)
    assert (second.in_ring, second.dropped) == (2, 2)
    check_golden(first.stats)
    check_golden(second.stats)


def test_samples_outside_every_run_count_in_the_seed_stats_only():
    store = AnalyticsStore()
    store.start_collection()
    for i in range(5):
        store.record(point(i, 0, 0, 0.0, 0.0, 2.0, 0.0, None, "manual"))  # standing still
    run = store.begin_run("manual", "", 10.0)
    store.record(point(10, 0, 0, 0.3, 0.0, 2.0, 0.0, run, "manual"))
    store.record(point(11, 0.1, 0, 0.3, 0.0, 1.9, 0.0, run, "manual"))
    assert store.stats().sampleCount == 7
    (summary,) = store.runs()
    assert summary.stats.sampleCount == 2 and summary.stats.avgLinearVel == pytest.approx(0.3)
    assert store.runs_by_algorithm()[0].stats.sampleCount == 2


def test_a_point_claiming_a_finished_run_joins_none():
    store = AnalyticsStore()
    store.start_collection()
    run = store.begin_run("go_to_goal", "square", 0.0)
    store.end_run(ABORTED, 1.0)
    store.record(point(2, *GOLDEN[0], run))
    assert store.runs() == () and store.points()[0].runId is None


def test_pooled_algorithm_rows_and_the_ranking_rule():
    log = RunLog()
    for algorithm, errors, outcome in [
        ("go_to_goal", [1.0, 1.0], COMPLETED),
        ("pure_pursuit", [0.5, 0.5], ABORTED),  # lowest error but never completed: not best
        ("go_to_goal", [3.0, 3.0], COMPLETED),
        ("pure_pursuit", [2.0, 2.0], COMPLETED),
    ]:
        run = log.begin(algorithm, "square", 0.0)
        for i, e in enumerate(errors):
            log.add(run, i, i, 0.0, 0.5, 0.0, e, 0.0)
        log.end(outcome, 1000.0, final_error_m=e / 10)
    runs = log.summaries()
    assert best_in(ranked(runs)) is runs[0]  # 1.0, completed
    g2g, pp = log.by_algorithm()
    assert isinstance(g2g, AlgorithmSummary) and (g2g.runs, g2g.completed) == (2, 2)
    assert g2g.stats.avgDistanceError == pytest.approx(2.0) and g2g.stats.sampleCount == 4
    assert g2g.stats.totalPathLength == pytest.approx(2.0)  # 1 m per run; no step between runs
    assert (pp.runs, pp.completed) == (2, 1) and pp.stats.avgDistanceError == pytest.approx(1.25)
    assert pp.time_s == pytest.approx(1.0) and pp.final_error_m == pytest.approx(0.2)
    assert best_in(ranked([g2g, pp])) is pp  # 1.25 < 2.0 among algorithms with a completed run
    marks = best_in_columns(runs)
    assert marks["avgDistanceError"] == {0} and marks["final_error_m"] == {0}
    assert "sampleCount" not in marks and "totalPathLength" not in marks
    assert "completed first" in RULE


def test_clear_forgets_runs_but_an_active_run_goes_on():
    store = AnalyticsStore()
    store.start_collection()
    run = store.begin_run("go_to_goal", "square", 0.0)
    store.record(point(1, *GOLDEN[0], run))
    store.clear()
    assert store.runs() == () and store.active_run == 1  # numbering starts again
    store.record(point(2, *GOLDEN[1], run))
    assert store.runs()[0].stats.sampleCount == 1


# -- the control loop says where runs begin and end -------------------------------------------------
class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def make_loop() -> tuple[ControlLoop, SimLink, AnalyticsStore, Clock]:
    clock = Clock()
    link = SimLink(clock=clock)
    store = AnalyticsStore(max_data_points=100_000)
    store.start_collection()
    return ControlLoop(link, store, Teleop(), wall_ms=lambda: clock.t * 1000.0), link, store, clock


def advance(loop: ControlLoop, link: SimLink, clock: Clock, seconds: float, keys: str = "") -> None:
    """Step the simulator at 50 Hz, control at 10 Hz, sample at 10 Hz; press ``keys`` every tick."""
    for _ in range(round(seconds * 50)):
        clock.t = round(clock.t + 0.02, 6)
        link.step()
        if round(clock.t * 50) % 5 == 0:
            for k in keys:
                loop.teleop.press(k, clock.t)
            loop.tick_control(clock.t)
            loop.sample()


def test_manual_driving_is_a_run_that_ends_after_two_idle_seconds():
    loop, link, store, clock = make_loop()
    advance(loop, link, clock, 1.0)  # standing still: no run
    assert store.runs() == () and store.active_run is None
    advance(loop, link, clock, 1.0, keys="i")
    assert store.active_run is not None
    advance(loop, link, clock, 1.5)  # idle, not yet 2 s
    assert store.active_run is not None
    advance(loop, link, clock, 1.0)
    assert store.active_run is None
    (run,) = store.runs()
    assert run.algorithm == "manual" and run.outcome == ENDED and run.mission == ""
    # first to last movement (the held key moves on for its grace after its last press, at most
    # key_timeout: teleop.py), not the idle tail
    assert 1.0 <= run.time_s <= 1.0 + loop.teleop.key_timeout
    assert run.stats.avgLinearVel == pytest.approx(0.5)  # idle samples are in no run
    assert store.stats().sampleCount > run.stats.sampleCount


def test_a_mission_run_completes_with_its_final_error():
    loop, link, store, clock = make_loop()
    loop.set_algorithm("go_to_goal")
    assert loop.go()
    advance(loop, link, clock, 60.0)
    (run,) = store.runs()
    assert run.outcome == COMPLETED and run.mission == "square"
    assert run.final_error_m is not None and run.final_error_m <= loop.mission.tolerance
    assert 5.0 < run.time_s < 60.0


def test_override_then_g_resumes_from_the_current_waypoint():
    loop, link, store, clock = make_loop()
    loop.set_algorithm("pure_pursuit")
    loop.go()
    advance(loop, link, clock, 8.0)
    reached = loop.mission.index
    assert 1 <= reached < 4
    first_goal = loop.mission.waypoints[0]
    loop.override()  # what a movement key does
    assert loop.algorithm == "manual" and not loop.running
    assert store.runs()[0].outcome == OVERRIDDEN
    assert loop.go()  # g: back to pure_pursuit, from the waypoint it was heading for
    assert loop.algorithm == "pure_pursuit" and loop.mission.index == reached
    assert loop.mission.waypoints[0] == first_goal  # the same mission, not one re-anchored here
    resumed = store.active_run
    assert resumed is not None and loop.mission_label == "square, resumed"
    assert loop.restart()  # the separate action starts again from waypoint 0, from here
    assert loop.mission.index == 0 and loop.mission_label == "square"
    # the resumed run recorded nothing before the restart: it is forgotten and its number reused
    assert store.active_run == resumed and store.run(resumed).mission == "square"


def test_go_to_a_point_selects_go_to_goal_and_reaches_it():
    loop, link, store, clock = make_loop()
    loop.go_to(1.0, -0.5)
    assert loop.algorithm == "go_to_goal" and loop.running
    advance(loop, link, clock, 20.0)
    pose = link.telemetry.snapshot()[0]
    assert math.hypot(pose.x - 1.0, pose.y + 0.5) <= loop.mission.tolerance
    (run,) = store.runs()
    assert run.completed and run.mission == "goal (+1.00, -0.50)"
    with pytest.raises(ValueError):
        loop.go_to(math.nan, 0.0)


def test_a_run_without_samples_is_not_listed_and_its_number_is_reused():
    store = AnalyticsStore()
    store.begin_run("go_to_goal", "square", 0.0)
    store.end_run(ABORTED, 1.0)
    assert store.runs() == () and store.run(1) is None
    assert store.begin_run("go_to_goal", "square", 2.0) == 1
