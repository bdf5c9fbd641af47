"""Answers a user can trust (issue 21): each test pins one item that was wrong before, through the code a
user's key, flag or file goes through. Pure logic and in-process commands; files in tmp_path."""

import json
import math
import os
from dataclasses import replace

import pytest

from arbiter_core.controllers import MISSIONS
from arbiter_core.record import LatencyRecord
from arbiter_tui.analytics import ranking
from arbiter_tui.analytics.files import export_store, load_points
from arbiter_tui.analytics.model import EMPTY_STATS, AnalyticsStats
from arbiter_tui.analytics.runs import ABORTED, COMPLETED, RunSummary
from arbiter_tui.analytics.store import AnalyticsStore, DataPoint
from arbiter_tui.cli import main
from arbiter_tui.control.loop import ControlLoop
from arbiter_tui.control.teleop import MIN_SPEED, MIN_TURN, Teleop
from arbiter_tui.latency.clocksync import LatencyMeter
from arbiter_tui.link.sim import SimLink
from arbiter_tui.session.compare import AUTONOMOUS, compare, run_one

from ..support.tui import FakeClock


def stats(e_d: float) -> AnalyticsStats:
    return replace(EMPTY_STATS, sampleCount=10, avgDistanceError=e_d)


def summary(run_id: int, algorithm: str, mission: str, e_d: float, done: bool = True) -> RunSummary:
    outcome = COMPLETED if done else ABORTED
    return RunSummary(run_id, algorithm, mission, 0.0, 1000.0, outcome, 0.1, stats(e_d), 10)


# -- 1. rankings compare like with like ----------------------------------------------------------
def test_rankings_never_mix_missions_and_overall_is_over_missions_all_completed():
    # pure_pursuit ran the easy figure eight and the square, go_to_goal the square only: pooled, pure
    # pursuit's figure-eight errors made it look best; like with like, go_to_goal wins the square
    entries = [
        summary(1, "pure_pursuit", "square", 1.15),
        summary(2, "pure_pursuit", "figure_eight", 0.40),
        summary(3, "go_to_goal", "square", 1.10),
        summary(4, "manual", "", 0.01, done=False),  # manual driving is never ranked
    ]
    answer = ranking.rank(entries)
    square, eight = answer.missions
    assert (square.mission, square.algorithms, square.best) == ("square", ("go_to_goal", "pure_pursuit"),
                                                                "go_to_goal")  # fmt: skip
    assert (eight.algorithms, eight.not_run) == (("pure_pursuit",), ("go_to_goal",))
    assert answer.overall.best == "go_to_goal" and answer.overall.missions == ("square",)
    assert "manual" not in {m.mission for m in answer.missions} | set(answer.overall.mean_rank)


def test_no_overall_best_without_a_mission_every_algorithm_completed_and_ties_are_said():
    answer = ranking.rank([summary(1, "a", "square", 1.0), summary(2, "b", "figure_eight", 0.4)])
    assert answer.overall.best is None and "no mission completed by every algorithm" in answer.overall.reason
    tie = ranking.rank([summary(1, "a", "m1", 1.0), summary(2, "b", "m1", 2.0), summary(3, "a", "m2", 2.0),
                        summary(4, "b", "m2", 1.0)])  # fmt: skip
    assert tie.overall.best is None and tie.overall.tied == ("a", "b") and "tie" in tie.overall.reason


def test_the_screens_rows_are_per_mission_and_algorithm():
    store = AnalyticsStore()
    store.start_collection()
    for mission, e in (("square", 1.0), ("figure_eight", 0.4)):
        run = store.begin_run("pure_pursuit", mission, 0.0)
        store.record(DataPoint(1.0, 0.0, 0.0, 0.0, 0.5, 0.0, e, 0.0, "pure_pursuit", None, run))
        store.end_run(COMPLETED, 2.0, 0.1)
    rows = store.runs_by_algorithm()
    assert [(r.mission, r.algorithm, r.stats.avgDistanceError) for r in rows] == [
        ("square", "pure_pursuit", 1.0), ("figure_eight", "pure_pursuit", 0.4)]  # fmt: skip


def test_compare_json_ranks_within_each_mission(capsys):
    assert main(["compare", "--json"]) == 0
    body = json.loads(capsys.readouterr().out)
    assert [m["mission"] for m in body["missions"]] == list(MISSIONS)
    assert all({r["mission"] for r in m["ranking"]} == {m["mission"]} for m in body["missions"])
    assert body["overall"]["missions"] == list(MISSIONS)
    assert body["overall"]["rule"] == ranking.RULE_OVERALL


# -- 3 and 4. idle time keeps out of the ring; paths never bridge gaps ------------------------------------
def drive(loop: ControlLoop, link: SimLink, clock: FakeClock, seconds: float) -> None:
    for n in range(round(seconds * 50)):
        clock.t = round(clock.t + 0.02, 6)
        link.step()
        if n % 5 == 4:
            loop.tick_control(clock.t)
            loop.sample()


def test_standing_still_after_missions_evicts_no_run_sample():
    clock = FakeClock(0.0)
    link = SimLink(clock=clock)
    store = AnalyticsStore(max_data_points=1000)
    store.start_collection()
    loop = ControlLoop(link, store, Teleop(), wall_ms=lambda: clock.t * 1000.0, max_rate=10.0)
    loop.set_algorithm("go_to_goal")
    loop.go()
    drive(loop, link, clock, 40.0)
    (run,) = store.runs()
    assert run.completed and run.in_ring == run.stats.sampleCount
    before = len(store)
    drive(loop, link, clock, 120.0)  # two minutes standing still: 1200 samples' worth of idle time
    assert store.run(run.id).in_ring == run.stats.sampleCount  # nothing evicted
    assert len(store) <= before + 2  # one sample where it stopped, no more


def test_path_length_never_spans_a_gap_between_stretches(tmp_path, capsys):
    # idle samples before and after a run, 0.144 m apart: the "no run" group has no path
    points = [DataPoint(1000.0 + i, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, "go_to_goal", None, None)
              for i in range(3)]  # fmt: skip
    points += [DataPoint(2000.0 + i, 0.05 * i, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, "go_to_goal", None, 1)
               for i in range(4)]  # fmt: skip
    points += [DataPoint(30000.0 + i, 0.144, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, "go_to_goal", None, None)
               for i in range(3)]  # fmt: skip
    from arbiter_tui.analytics.exports import to_csv

    f = tmp_path / "gaps.csv"
    f.write_text(to_csv(points))
    assert main(["stats", str(f), "--by", "run", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["no run"]["totalPathLength"] == 0.0
    assert got["run 1"]["totalPathLength"] == pytest.approx(0.15)
    assert main(["stats", str(f), "--by", "algorithm", "--json"]) == 0
    by_algo = json.loads(capsys.readouterr().out)  # idle samples belong to no algorithm
    assert by_algo["go_to_goal"]["sampleCount"] == 4


# -- 2. stats --by run/algorithm agree with the screen --------------------------------------------------
def small_ring_store() -> AnalyticsStore:
    """One go_to_goal square run of ~200 samples, idle samples around it, in a ring of 150."""
    store = AnalyticsStore(max_data_points=150)
    store.start_collection()
    result = run_one("go_to_goal", "square")
    idle = DataPoint(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, "go_to_goal", None, None)
    store.record(idle)
    run = store.begin_run("go_to_goal", "square", 1.0)
    for p in result.points:
        store.record(replace(p, timestamp=p.timestamp + 10.0, runId=run))
    store.end_run(COMPLETED, result.points[-1].timestamp + 10.0, result.final_error_m)
    store.record(replace(idle, timestamp=1e6))
    return store


@pytest.mark.parametrize("fmt", ["json", "mcap"])
def test_stats_by_run_reports_the_whole_run_and_marks_a_partial_file(tmp_path, capsys, fmt):
    store = small_ring_store()
    (run,) = store.runs()
    assert run.dropped > 0
    path = export_store(store, fmt, tmp_path)
    assert main(["stats", str(path), "--by", "run", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["run 1"]["sampleCount"] == run.stats.sampleCount
    assert got["run 1"]["avgDistanceError"] == pytest.approx(run.stats.avgDistanceError)
    assert got["run 1"]["totalPathLength"] == pytest.approx(run.stats.totalPathLength)
    assert got["run 1"]["samplesInFile"] == run.in_ring
    assert main(["stats", str(path), "--by", "run"]) == 0
    out = capsys.readouterr().out
    assert f"[run 1 go_to_goal on square]  in file {run.in_ring}/{run.stats.sampleCount}" in out
    assert main(["stats", str(path), "--by", "algorithm", "--json"]) == 0
    (row,) = store.runs_by_algorithm()
    by_algo = json.loads(capsys.readouterr().out)
    assert by_algo["go_to_goal on square"]["sampleCount"] == row.stats.sampleCount
    assert by_algo["go_to_goal on square"]["avgDistanceError"] == pytest.approx(row.stats.avgDistanceError)


def test_a_run_whose_samples_all_left_the_file_is_still_listed(tmp_path, capsys):
    store = AnalyticsStore(max_data_points=5)
    store.start_collection()
    run = store.begin_run("go_to_goal", "square", 0.0)
    for i in range(10):
        store.record(DataPoint(float(i), 0.1 * i, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, "go_to_goal", None, run))
    store.end_run(COMPLETED, 10.0, 0.1)
    run2 = store.begin_run("manual", "", 20.0)
    for i in range(5):  # a manual stretch fills the ring
        store.record(DataPoint(20.0 + i, 1.0, 0.1 * i, 0.0, 0.5, 0.0, 1.0, 0.0, "manual", None, run2))
    path = export_store(store, "json", tmp_path)
    assert main(["stats", str(path), "--by", "run", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["run 1"]["sampleCount"] == 10 and got["run 1"]["samplesInFile"] == 0


# -- 6. run numbers without holes --------------------------------------------------------------------------
def test_runs_made_while_paused_take_no_number():
    store = AnalyticsStore()
    for _ in range(2):  # paused: two runs that record nothing
        store.begin_run("go_to_goal", "square", 0.0)
        store.end_run(ABORTED, 1.0)
    store.start_collection()
    run = store.begin_run("pure_pursuit", "square", 2.0)
    store.record(DataPoint(3.0, 0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, "pure_pursuit", None, run))
    store.end_run(COMPLETED, 4.0, 0.1)
    assert run == 1 and [r.id for r in store.runs()] == [1]


# -- 7. a flood of queued reports fakes no clock offset ---------------------------------------------------
def test_queueing_does_not_enter_the_offset_and_late_reports_are_not_lost():
    meter = LatencyMeter()
    stamp0 = 1_800_000_000_000.0
    seq = 0

    def exchange(at: float, rtt_ms: float, raw_ms: float) -> None:
        nonlocal seq
        stamp = stamp0 + at * 1000.0
        meter.on_send(seq, stamp, at)
        meter.on_report(LatencyRecord(raw_ms, 0.0, 0.0, (stamp + raw_ms) / 1000.0, "native", seq=seq),
                        at + rtt_ms / 1000.0)  # fmt: skip
        seq += 1

    for i in range(20):  # a quiet link: rtt 1 ms, clocks in step
        exchange(i * 0.1, 1.0, 0.5)
    for i in range(5000):  # a flood: reports queue behind commands for ~1.9 s
        exchange(2.0 + i * 0.002, 1900.0, 0.5)
    est = meter.offset()
    # the flood's exchanges (delay 1.9 s) are left out: the offset is the quiet link's, from a 1 ms
    # exchange; its bound is that exchange's 0.5 ms plus what a 500 ppm drift could add in the ~13 s since
    assert est is not None and abs(est.offset_ms) < 1.0 and est.rtt_ms == pytest.approx(1.0)
    assert est.uncertainty_ms <= 0.5 + 0.5 * 13.0
    assert not est.significant(10.0)
    # a command reported after the loss deadline was queued, not lost on the link
    meter.on_send(seq, stamp0, 100.0)
    assert meter.expire(103.0) == 1 and meter.lost == 1
    meter.on_report(LatencyRecord(0.5, 0.0, 0.0, (stamp0 + 0.5) / 1000.0, "native", seq=seq), 104.0)
    assert (meter.lost, meter.late, meter.lost_in_window()) == (0, 1, 0)


def test_a_real_offset_is_alarmed_only_when_sure():
    meter = LatencyMeter()
    for i in range(10):
        meter.on_send(i, 1e12 + i, float(i))
        raw = 25.0 + 1.0  # tracker 25 ms ahead, 1 ms one way
        meter.on_report(LatencyRecord(raw, 0.0, 0.0, (1e12 + i + raw) / 1000.0, "native", seq=i), i + 0.002)
    est = meter.offset()
    assert est is not None and est.offset_ms == pytest.approx(25.0) and est.significant(10.0)


# -- 13, 14, 15. flags and keys that cannot hurt -----------------------------------------------------------
def test_every_controller_honours_the_speed_cap(capsys):
    assert main(["compare", "--json", "--speed", "0.8", "--mission", "square"]) == 0
    body = json.loads(capsys.readouterr().out)
    fastest = {r["algorithm"]: r["max_linear_vel"] for r in body["runs"]}
    assert fastest == dict.fromkeys(AUTONOMOUS, 0.8)  # each reaches the cap, none goes past it


def test_a_capped_speed_is_said_once(capsys):
    assert main(["compare", "--json", "--speed", "100", "--mission", "square"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["arbiter-tui compare: speed 100 → 1 m/s, the robot's limit"]


def test_scaling_down_stops_at_a_visible_floor():
    teleop = Teleop()
    for _ in range(200):
        teleop.press("z", 0.0)
    assert (teleop.speed, teleop.turn) == (MIN_SPEED, MIN_TURN)
    teleop.press("i", 0.0)
    assert teleop.target[0] == MIN_SPEED > 0


def test_key_repeats_never_outrun_the_repeat_rate():
    class Counting:
        def __init__(self):
            from arbiter_tui.link.base import Telemetry

            self.telemetry = Telemetry()
            self.state = "CONNECTED"
            self.sent = []

        def send(self, v, w):
            self.sent.append((v, w))
            return True

        def close(self):
            pass

    link = Counting()
    teleop = Teleop()
    loop = ControlLoop(link, AnalyticsStore(), teleop, max_rate=10.0)
    t = 0.0
    while t < 2.0:  # a key repeating every 50 ms, each answered at once, plus the 10 Hz tick
        teleop.press("i" if int(t * 20) % 2 else "j", t)
        loop.tick_control(t)
        if round(t * 20) % 2 == 0:
            loop.tick_control(t)
        t = round(t + 0.05, 6)
    moving = [c for c in link.sent if c != (0.0, 0.0)]
    assert len(moving) <= 2.0 * 10 + 2  # the rate is a ceiling (a burst of two at most)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--repeat-rate", "100000"], "--repeat-rate: must be in [2, 50] Hz"),
        (["--key-timeout", "1e9"], "--key-timeout: must be in [0.1, 2] s"),
        (["--collection-rate", "100000"], "--collection-rate: must be in (0, 100] Hz"),
        (["--offset-warn-ms", "nan"], "--offset-warn-ms: must be in"),
        (["--sim", "--log-file", "/nonexistent/d/x.log"], "--log-file /nonexistent/d/x.log: No such file"),
    ],
)
def test_bad_numbers_are_one_line_errors_before_the_console_starts(capsys, args, words):
    try:
        code = main(args)
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0], err


def test_config_keys_have_the_same_bounds(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text("repeat-rate = 1000\n")
    assert main(["--config", str(cfg), "--sim"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert f"{cfg}:1: repeat-rate: " in line and "must be in [2, 50] Hz" in line


def test_help_names_the_subcommands(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "arbiter-tui compare" in out and "arbiter-tui stats FILE" in out


# -- 16. exports ------------------------------------------------------------------------------------------
def test_an_empty_store_exports_nothing(tmp_path):
    from arbiter_tui.analytics.files import NothingToExport

    with pytest.raises(NothingToExport, match="0 samples"):
        export_store(AnalyticsStore(), "csv", tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_exports_respect_the_umask(tmp_path):
    store = small_ring_store()
    old = os.umask(0o022)
    try:
        path = export_store(store, "csv", tmp_path)
    finally:
        os.umask(old)
    assert path.stat().st_mode & 0o777 == 0o644


def test_compare_runs_each_have_their_own_time_span():
    results = compare(["square"], ["go_to_goal", "pure_pursuit"], t0_ms=1_800_000_000_000.0)
    spans = [(r.points[0].timestamp, r.points[-1].timestamp) for r in results]
    assert spans[0][0] >= 1_800_000_000_000.0
    assert spans[0][1] < spans[1][0]  # the second starts after the first ended
    assert len({p.timestamp for r in results for p in r.points}) == sum(len(r.points) for r in results)


def test_compare_exports_are_in_this_century(tmp_path, capsys):
    assert main(["compare", "--mission", "square", "--json", "--export-dir", str(tmp_path)]) == 0
    body = json.loads(capsys.readouterr().out)
    points = load_points(next(p for p in body["exports"] if p.endswith(".mcap")))
    assert min(p.timestamp for p in points) > 1_700_000_000_000.0  # 2023, not 1970
    assert math.isclose(len({p.timestamp for p in points}), len(points))
