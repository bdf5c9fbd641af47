"""The fleet's rows (arbiter_tui.fleet.rows): states, never dropping a robot, bad data, severity, filter."""

import pytest

from arbiter_core import fleet
from arbiter_core.timesync import TimeSync
from arbiter_tui.fleet.rows import (
    BAD_HOLD_S,
    COLUMNS,
    MAX_ROBOTS,
    WARN,
    FleetModel,
    cells,
    console_argv,
    detail_lines,
    history_words,
    matches,
    state_cell,
)

W = 1_800_000_000.0  # wall s


def status(name, **kw):
    base = dict(
        robot=name,
        t=W,
        started=W - 100,
        driver="nobody",
        mode="embedded, sim",
        rosbridge=f"ws://{name}:9090",
        tracker=f"http://{name}:8085",
    )
    return fleet.Status(**{**base, **kw})


def latency(name, ok=True, err=0.5, p95=4.0):
    return fleet.Latency(
        name,
        W,
        count=10,
        total=10,
        p50_ms=2.0,
        p95_ms=p95,
        sync_source="chrony",
        sync_ok=ok,
        sync_error_ms=err,
    )


def topics(name, *health):
    items = tuple(fleet.TopicHealth(f"/t{i}", h) for i, h in enumerate(health))
    return fleet.Topics(name, W, 5.0, len(items), items)


def alive(model, name, mono=0.0, **kw):
    model.token(name, True, W + mono, mono)
    model.accept(status(name, **kw), 300, mono)


def by_name(view):
    return {r.name: r for r in view.rows}


def test_a_robot_goes_alive_stale_lost_and_back_and_is_never_dropped():
    m = FleetModel(stale_after=5.0)
    alive(m, "r1", 0.0)
    assert by_name(m.view(W, 1.0))["r1"].state == "alive"
    assert by_name(m.view(W, 6.0))["r1"].state == "stale"  # no status for 5 s, token still there
    m.token("r1", False, W + 7, 7.0)
    row = by_name(m.view(W + 3600, 3600.0))["r1"]  # an hour later: still listed
    assert (row.state, row.since, row.severity) == ("lost", W + 7, 4)
    assert cells(row)[1].startswith("lost since ")
    m.token("r1", True, W + 3601, 3601.0)
    assert by_name(m.view(W, 3601.5))["r1"].state == "alive"  # back, waiting for its status
    assert by_name(m.view(W, 3607.0))["r1"].state == "stale"  # ...which did not come
    m.accept(status("r1"), 300, 3607.5)
    assert by_name(m.view(W, 3608.0))["r1"].state == "alive"


def test_payloads_without_a_token_are_listed_stale_and_say_why():
    m = FleetModel()
    m.accept(status("ghost"), 300, 0.0)
    row = by_name(m.view(W, 0.5))["ghost"]
    assert (row.state, row.note) == ("stale", "no liveliness token (payloads only)")


def test_bad_data_marks_only_its_row_and_fades_after_the_hold():
    m = FleetModel()
    alive(m, "r1")
    alive(m, "r2")
    m.accept(latency("r1"), 200, 0.0)
    m.reject("r1", "status: not JSON (Expecting value)", 1.0)
    rows = by_name(m.view(W, 2.0))
    assert rows["r1"].bad == "status: not JSON (Expecting value)" and rows["r1"].severity == 3
    assert rows["r1"].p95_ms == 4.0  # the last good figures stay
    assert cells(rows["r1"])[-1] == "bad data: status: not JSON (Expecting value)"
    assert rows["r2"].bad is None and rows["r2"].severity == 0
    m.accept(status("r1"), 300, 1.0 + BAD_HOLD_S)
    later = by_name(m.view(W, 1.0 + BAD_HOLD_S + 1))["r1"]
    assert later.bad is None and later.bad_count == 1


def test_severity_orders_rows_lost_bad_stale_warning_ok_then_by_name():
    m = FleetModel(stale_after=5.0)
    for name in ("ok-b", "ok-a", "warn", "bad", "stale", "lost"):
        alive(m, name, 0.0)
    m.accept(status("ok-a"), 300, 9.0)
    m.accept(status("ok-b"), 300, 9.0)
    m.accept(status("warn"), 300, 9.0)
    m.accept(topics("warn", "below", "ok"), 300, 9.0)
    m.accept(status("bad"), 300, 9.0)
    m.reject("bad", "latency: NaN", 9.0)
    m.token("lost", False, W + 8, 8.0)
    assert [r.name for r in m.view(W, 10.0).rows] == ["lost", "bad", "stale", "warn", "ok-a", "ok-b"]
    counts = dict(m.view(W, 10.0).counts)
    assert counts == {"alive": 4, "stale": 1, "lost": 1, "unknown": 0, "bad": 1}


@pytest.mark.parametrize(
    ("pattern", "shown"),
    [
        ("", ["lab-1", "lab-2", "yard-1"]),
        ("lab-*", ["lab-1", "lab-2"]),
        ("*-1", ["lab-1", "yard-1"]),
        ("YARD", ["yard-1"]),
        ("lab-[2]", ["lab-2"]),
        ("nothing", []),
    ],
)
def test_the_filter_is_a_name_glob_and_counts_stay_over_all(pattern, shown):
    m = FleetModel()
    for name in ("yard-1", "lab-2", "lab-1"):
        alive(m, name)
    view = m.view(W, 0.5, pattern)
    assert [r.name for r in view.rows] == shown
    assert view.total == 3 and dict(view.counts)["alive"] == 3
    assert all(matches(n, pattern) for n in shown)


def test_a_flood_of_names_is_counted_not_listed():
    m = FleetModel()
    for i in range(MAX_ROBOTS + 50):
        m.token(f"r{i}", True, W, 0.0)
    view = m.view(W, 0.1)
    assert view.total == MAX_ROBOTS and view.ignored == 50


def test_the_clock_bound_needs_both_hosts_synchronised():
    m = FleetModel()
    alive(m, "r1")
    m.accept(latency("r1", ok=True, err=0.5), 200, 0.0)
    assert by_name(m.view(W, 0.1))["r1"].clock_note == "this host's clock not synchronised"
    m.console_sync = TimeSync("chrony", True, 0.01, 0.25)
    assert by_name(m.view(W, 0.1))["r1"].offset_bound_ms == 0.75
    m.accept(latency("r1", ok=False, err=None), 200, 0.2)
    assert by_name(m.view(W, 0.3))["r1"].clock_note == "robot clock not synchronised"


def test_the_history_backfills_figures_but_never_older_ones_or_the_status():
    m = FleetModel()
    m.token("r1", True, W, 0.0)
    newer = fleet.Latency("r1", W + 10, count=5, total=5, p50_ms=1.0, p95_ms=1.0)
    m.accept(newer, 200, 0.0)
    old_lat = fleet.Latency("r1", W, count=9, total=9, p50_ms=9.0, p95_ms=9.0)
    grade = fleet.RunGrade(2, "stanley", "slalom", "aborted", 12.0, 3, 7, None, W - 5)
    m.backfill(
        fleet.History(
            "r1", W, 1.0, (status("r1"), old_lat, topics("r1", "slow"), fleet.Runs("r1", W, 2, grade))
        ),
        0.1,
    )
    row = by_name(m.view(W, 0.2))["r1"]
    assert row.p95_ms == 1.0  # the live one, newer, kept
    assert (row.worst_topic, row.runs, row.grade) == ("/t0 slow", 2, "aborted 3/7 12.0 s")
    assert row.driver is None and row.note == "no status yet"  # the past status is not taken


def test_the_console_opens_a_robot_on_its_advertised_urls():
    m = FleetModel()
    alive(m, "r1", namespace="/lab/r1")
    row = by_name(m.view(W, 0.1))["r1"]
    assert console_argv(row) == [
        "--robot-name",
        "r1",
        "--rosbridge",
        "ws://r1:9090",
        "--tracker",
        "http://r1:8085",
        "--namespace",
        "/lab/r1",
    ]
    alive(m, "r2", auth="token")
    r2 = by_name(m.view(W, 0.1))["r2"]
    assert console_argv(r2) == "r2 wants its token: start the fleet with --token-file FILE"
    assert console_argv(r2, token_file="/t")[-2:] == ["--token-file", "/t"]
    m.token("r1", False, W + 5, 5.0)
    assert "r1 is lost since" in console_argv(by_name(m.view(W, 6.0))["r1"])
    alive(m, "r3", rosbridge=None)
    assert "advertises no rosbridge URL" in console_argv(by_name(m.view(W, 6.0))["r3"])


def test_json_rows_carry_the_cells_the_screen_shows():
    m = FleetModel()
    alive(m, "r1", driver="robot", controller="pure_pursuit", run_state="running", waypoint=2, waypoints=4)
    m.accept(latency("r1", p95=12.345), 200, 0.0)
    view = m.view(W, 1.0)
    row = view.rows[0]
    obj = view.to_json()["robots"][0]
    assert obj["cells"] == dict(zip(COLUMNS, cells(row), strict=True))
    assert obj["cells"]["controller"] == "pure_pursuit 2/4 running"
    assert obj["cells"]["p95"] == "12.3 ms"
    assert detail_lines(row, W)[0].startswith("r1  alive (announced since")  # 1 s old: not late
    assert state_cell(m.view(W, 2.5).rows[0]) == "alive 2s"


def test_history_in_one_line():
    grade = fleet.RunGrade(1, "stanley", "square", "completed", 30.0, 4, 4, 0.1, W)
    h = fleet.History(
        "r1", W, 10.0, (latency("r1", p95=2.0), latency("r1", p95=5.0), fleet.Runs("r1", W, 1, grade))
    )
    assert history_words(h) == (
        "history (10 min): 3 summaries, p95 2-5 ms, 1 runs, last stanley completed 30.0 s, 0.10 m"
    )
    assert history_words("r1 did not answer in 3 s") == "history: r1 did not answer in 3 s"


def test_a_robot_whose_topic_monitor_restarts_says_so_not_that_its_topics_are_silent():
    m = FleetModel()
    alive(m, "r1")
    m.accept(
        fleet.Topics("r1", W, 5.0, 2, (fleet.TopicHealth("/odom", "unknown"),), "monitor restarted: E: x"),
        200,
        0.0,
    )
    row = by_name(m.view(W, 0.1))["r1"]
    assert (row.worst_topic, row.worst_health) == ("monitor restarted: E: x", "unknown")
    assert row.severity == WARN
    assert "monitor restarted: E: x" in cells(row)
