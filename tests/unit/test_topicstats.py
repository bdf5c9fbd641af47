"""Topic figures (rate, bandwidth, delay, age, state) from synthetic receive times; the API's parsing."""

import math

import pytest

from arbiter_core.topicstats import (
    NOT_INSTALLED,
    RATE_HISTORY,
    TopicsError,
    TopicWindow,
    parse_expect,
    parse_topics,
    qos_mismatch,
    unmet,
)


def fed(hz: float, seconds: float, size: int = 100, window: float = 5.0, start: float = 100.0) -> TopicWindow:
    w = TopicWindow("/t", "std_msgs/msg/String", window)
    n = int(seconds * hz)
    for i in range(n):
        w.add(start + i / hz, size)
    return w


def test_rate_bandwidth_and_period_of_a_steady_topic():
    w = fed(50.0, 8.0, size=600)
    now = 100.0 + 8.0
    f = w.figures(now)
    assert f.rate_hz == pytest.approx(50.0)
    assert f.bandwidth_bps == pytest.approx(50.0 * 600)  # mean size x rate for a steady publisher
    assert f.mean_size_bytes == 600
    assert f.period_min_ms == pytest.approx(20.0) and f.period_max_ms == pytest.approx(20.0)
    assert f.period_std_ms == pytest.approx(0.0, abs=1e-6)
    assert f.count == 250 and f.total == 400  # only the last 5 s are in the window
    assert f.state == "ok" and f.age_ms == pytest.approx(20.0)


def test_jitter_shows_in_the_period_spread_not_the_mean_rate():
    w = TopicWindow("/t", "x", 5.0)
    t = 0.0
    for i in range(100):
        t += 0.08 if i % 2 else 0.12  # 10 Hz on average
        w.add(t, 10)
    f = w.figures(t)
    assert f.rate_hz == pytest.approx(10.0, rel=0.01)
    assert f.period_min_ms == pytest.approx(80.0) and f.period_max_ms == pytest.approx(120.0)
    assert f.period_std_ms == pytest.approx(20.0, rel=0.01)


def test_delay_mean_and_p95_from_stamped_messages():
    w = TopicWindow("/t", "nav_msgs/msg/Odometry", 5.0, stamped=True)
    for i in range(100):
        w.add(i * 0.02, 700, delay_s=0.020 + (0.010 if i >= 95 else 0.0))
    f = w.figures(2.0)
    assert f.stamped
    assert f.delay_mean_ms == pytest.approx(20.5)
    assert f.delay_p95_ms == pytest.approx(30.0)  # the seed's percentile: sorted[floor(n * 0.95)]


def test_states_waiting_silent_slow_ok_and_unmeasured():
    w = TopicWindow("/t", "x", 2.0)
    assert w.figures(0.0).state == "waiting"
    for i in range(60):  # 10 Hz for 6 s: a full window, so the usual rate is learnt
        w.add(i / 10, 10)
    assert w.figures(5.95).state == "ok"
    assert w.figures(5.95).usual_rate_hz == pytest.approx(10.0)
    for i in range(10):  # then 2 Hz
        w.add(6.0 + i / 2, 10)
    assert w.figures(10.5).state == "slow"
    assert w.figures(20.0).state == "silent"  # steady from its first message, then stopped
    assert w.figures(20.0).rate_hz is None and w.figures(20.0).count == 0
    u = TopicWindow("/img", "sensor_msgs/msg/Image", 2.0)
    u.unmeasured = NOT_INSTALLED
    assert u.figures(1.0).state == "unmeasured" and u.figures(1.0).note == NOT_INSTALLED


def test_age_is_now_minus_the_last_message_even_once_the_window_is_empty():
    """A topic silent longer than the window still has an age: how long ago its last message came."""
    w = TopicWindow("/scan", "sensor_msgs/msg/LaserScan", 2.0)
    assert w.figures(1.0).age_ms is None  # never a message: no age
    for i in range(50):  # 10 Hz for 5 s, the last at 4.9 s
        w.add(i / 10, 10)
    assert w.figures(5.0).age_ms == pytest.approx(100.0)
    for now in (7.0, 30.0, 600.0):  # the window emptied at 6.9 s
        f = w.figures(now)
        assert f.count == 0 and f.age_ms == pytest.approx((now - 4.9) * 1e3)
    w.add(600.5, 10)  # it speaks again
    assert w.figures(601.0).age_ms == pytest.approx(500.0)


def walk(w: TopicWindow, arrivals: list[float], until: float, step: float = 0.1) -> list[tuple[float, str]]:
    """The state at every ``step`` of a clock from the first arrival to ``until``, as a 2 Hz poller (or a
    faster one) would see it; the arrivals are fed as the clock passes them."""
    pending, out, t = sorted(arrivals), [], 0.0
    while t <= until + 1e-9:
        while pending and pending[0] <= t:
            w.add(pending.pop(0), 10)
        out.append((round(t, 3), w.figures(t).state))
        t += step
    return out


def steady(start: float, end: float, hz: float, jitter: float = 0.0, seed: int = 1) -> list[float]:
    import random

    rnd, t, out = random.Random(seed), start, []
    while t < end:
        out.append(t)
        t += (1.0 + rnd.uniform(-jitter, jitter)) / hz
    return out


def test_a_steady_topic_that_stops_is_silent_after_five_of_its_periods_and_a_second_at_least():
    """A 10 Hz scan with ±30 % jitter, from the moment it is on the graph: a sensor. It stops at 20 s."""
    w = TopicWindow("/scan", "sensor_msgs/msg/LaserScan", 5.0, created=0.0)
    arrivals = steady(0.3, 20.0, 10.0, jitter=0.3)
    states = dict(walk(w, arrivals, 30.0))
    last = arrivals[-1]
    assert {s for t, s in states.items() if 0.3 <= t < last} == {"ok"}
    assert states[round(last + 0.55, 1)] == "ok"  # five periods, but less than STOP_MIN_S
    assert all(s == "silent" for t, s in states.items() if t >= last + 1.0)
    f = w.figures(30.0)
    assert f.state == "silent" and f.rate_hz is None


def test_bursts_of_commands_then_quiet_are_quiet_never_silent():
    """/stamped_cmd_vel as teleop makes it: on the graph from the start, 10 Hz while a key is held (holds
    of 2, 3.5 and 6 s), one zero after each, and the tracker's zero 0.5 s later; then the robot stands."""
    w = TopicWindow("/stamped_cmd_vel", "std_msgs/msg/String", 5.0, created=0.0)
    arrivals = []
    for start, end in ((10.0, 12.0), (15.0, 18.5), (30.0, 36.0)):
        hold = steady(start, end, 10.0)
        arrivals += [*hold, hold[-1] + 0.1, hold[-1] + 0.6]
    states = walk(w, arrivals, 90.0)
    assert "silent" not in {s for _, s in states}
    assert states[-1][1] == "quiet" and w.figures(90.0).state == "quiet"
    assert ("ok" in {s for t, s in states if 30 < t < 36}) and w.figures(90.0).total == len(arrivals)


def test_a_mission_that_ends_is_quiet_but_a_minute_of_steady_publishing_makes_a_sensor():
    """A topic that waited on the graph before it published (a console's commands) is on demand: a 30 s
    mission at 10 Hz that ends is quiet. Steady for a minute, it is steady whatever came before."""
    mission = TopicWindow("/cmd_vel_measured", "geometry_msgs/msg/Twist", 5.0, created=0.0)
    arrivals = steady(20.0, 50.0, 10.0)
    assert "silent" not in {s for _, s in walk(mission, arrivals, 70.0)}
    assert mission.figures(70.0).state == "quiet"
    long_run = TopicWindow("/cmd_vel_measured", "geometry_msgs/msg/Twist", 5.0, created=0.0)
    arrivals = steady(20.0, 81.0, 10.0)
    states = dict(walk(long_run, arrivals, 90.0))
    assert states[90.0] == "silent" and states[round(arrivals[-1] + 0.5, 1)] == "ok"
    # the same 30 s from the moment it appeared on the graph: a sensor that died
    sensor = TopicWindow("/scan", "sensor_msgs/msg/LaserScan", 5.0, created=19.5)
    walk(sensor, steady(20.0, 50.0, 10.0), 52.0)
    assert sensor.figures(52.0).state == "silent"


def test_an_irregular_topic_that_goes_quiet_is_quiet():
    """/rosout: messages at random (exponential gaps, 2 per second on average) for a minute, then none."""
    import random

    rnd, t, arrivals = random.Random(7), 0.2, []
    while t < 60.0:
        arrivals.append(t)
        t += rnd.expovariate(2.0)
    w = TopicWindow("/rosout", "rcl_interfaces/msg/Log", 5.0, created=0.0)
    states = walk(w, arrivals, 80.0)
    assert "silent" not in {s for _, s in states} and states[-1][1] == "quiet"


def test_the_usual_rate_decays_so_a_new_steady_rate_becomes_usual():
    w = TopicWindow("/t", "x", 2.0)
    t = 0.0
    for _ in range(60):
        w.add(t, 1)
        t += 0.1
    w.figures(t)  # usual = 10 Hz
    for _ in range(3000):  # 5 minutes at 5 Hz
        w.add(t, 1)
        t += 0.2
        if int(t * 5) % 50 == 0:
            w.figures(t)
    f = w.figures(t)
    assert f.rate_hz == pytest.approx(5.0, rel=0.01)
    assert f.state == "ok", f.usual_rate_hz


def test_the_rate_history_holds_one_sample_a_second_over_the_last_minute():
    w = TopicWindow("/scan", "sensor_msgs/msg/LaserScan", 5.0)
    sampled = []
    for i in range(1000):  # 10 Hz for 100 s, then 5 Hz; sampled twice a second
        w.add(i / 10, 10)
        if i % 5 == 0:
            w.sample(i / 10)
            sampled.append(len(w.rate_history))
    t = 100.0
    assert sampled[:9] == [1, 1, 2, 2, 3, 3, 4, 4, 5]  # once a second, however often it is called
    assert len(w.rate_history) == RATE_HISTORY  # bounded: the last minute
    assert all(r == pytest.approx(10.0) for r in w.rate_history)
    for i in range(50):
        w.add(t + i * 0.2, 10)
    w.sample(t + 10.0)  # ten seconds late: the seconds it missed take the rate now
    f = w.figures(t + 10.0)
    assert f.rate_history[-10:] == (pytest.approx(5.0),) * 10 and len(f.rate_history) == RATE_HISTORY
    w.sample(t + 30.0)  # stopped: no rate in the window
    assert w.figures(t + 30.0).rate_history[-1] is None
    assert f.to_json()["rate_history"][-1] == pytest.approx(5.0)


def test_the_rate_history_is_parsed_bounded_and_checked():
    body = {"window_s": 5, "topics": [
        good(rate_history=[None, 1.5, 2]),
        good(name="/long", rate_history=list(range(100))),
        good(name="/old"),  # a backend that predates it
        good(name="/bad", rate_history=[1.0, "fast"]),
        good(name="/neg", rate_history=[-1.0]),
    ]}  # fmt: skip
    answer = parse_topics(body)
    by = {t.name: t for t in answer.topics}
    assert by["/odom"].rate_history == (None, 1.5, 2.0)
    assert by["/long"].rate_history == tuple(float(i) for i in range(40, 100))
    assert by["/old"].rate_history == () and answer.skipped == 2


def test_qos_mismatch_notes():
    assert qos_mismatch([("best_effort", "volatile")], [("reliable", "volatile")]) == (
        "a reliable subscriber cannot match a best-effort publisher"
    )
    assert "transient-local subscriber" in qos_mismatch(
        [("reliable", "volatile")], [("reliable", "transient_local")]
    )
    assert qos_mismatch([("reliable", "transient_local")], [("best_effort", "volatile")]) is None


def good(**over):
    row = {"name": "/odom", "type": "nav_msgs/msg/Odometry", "state": "ok", "rate_hz": 50.0, "count": 250,
           "total": 400, "publishers": 1, "subscribers": 2, "stamped": True,
           "delay_mean_ms": 20.1}  # fmt: skip
    row.update(over)
    return row


def test_parse_topics_takes_good_rows_and_counts_bad_ones():
    answer = parse_topics(
        {
            "window_s": 5,
            "topics": [
                good(),
                good(name="/scan", rate_hz=math.inf),  # not JSON, but a Python caller could: refused
                good(name="/x", state="dead"),
                good(name="/y", count=-1),
                good(name="/z", rate_hz="fast"),
                "nope",
                good(name="/a", rate_hz=None, state="silent", publisher_nodes=["/driver"]),
                good(name="/b", subscriber_nodes="/console"),  # not a list
            ],
        }
    )
    assert [t.name for t in answer.topics] == ["/a", "/odom"]
    assert answer.skipped == 6 and answer.window_s == 5.0
    assert answer.topics[0].publisher_nodes == ("/driver",) and answer.topics[1].publisher_nodes == ()
    odom = answer.topics[1]
    assert odom.rate_hz == 50.0 and odom.stamped and odom.subscribers == 2


@pytest.mark.parametrize("body", [None, [], {"topics": []}, {"window_s": 0, "topics": []}, {"window_s": 5}])
def test_parse_topics_refuses_what_is_not_an_answer(body):
    with pytest.raises(TopicsError):
        parse_topics(body)


def test_expectations_parse_and_name_each_unmet_topic():
    exp = parse_expect("/scan>=9.5, /odom>=45")
    assert [(e.topic, e.min_hz) for e in exp] == [("/scan", 9.5), ("/odom", 45.0)]
    answer = parse_topics({"window_s": 5, "topics": [good(rate_hz=44.0), good(name="/imu", rate_hz=100.0)]})
    reasons = unmet(exp, answer)
    assert reasons == [
        "/scan: not on the graph (expected >= 9.5 Hz)",
        "/odom: 44.00 Hz in the last 5 s, expected >= 45 Hz",
    ]
    assert unmet(parse_expect("/imu>=99"), answer) == []
    held = parse_topics(
        {"window_s": 5, "topics": [good(rate_hz=50.0, state="unknown", note="monitor restarted: E")]}
    )
    assert unmet(parse_expect("/odom>=45"), held) == [
        "/odom: not known now (monitor restarted: E), expected >= 45 Hz"
    ]
    for bad in ("scan>=9", "/scan>9", "/scan>=fast", "/scan>=-1", "/scan>=nan", ",,"):
        with pytest.raises(ValueError):
            parse_expect(bad)


def test_while_the_monitor_restarts_a_topic_is_unknown_with_the_reason_and_the_answer_says_so():
    from arbiter_core.topicstats import unknown

    f = fed(50.0, 8.0).figures(108.0)
    held = unknown(f, "monitor restarted: OSError: gone")
    assert (held.state, held.note, held.rate_hz) == ("unknown", "monitor restarted: OSError: gone", f.rate_hz)
    cannot = TopicWindow("/x", "a/msg/B")
    cannot.unmeasured = NOT_INSTALLED
    assert unknown(cannot.figures(1.0), "monitor restarted: x").state == "unmeasured"  # why stays its own
    answer = parse_topics({"window_s": 5, "interrupted": held.note, "topics": [held.to_json()]})
    assert answer.interrupted == "monitor restarted: OSError: gone" and answer.skipped == 0
    assert answer.topics[0].state == "unknown"
    assert parse_topics({"window_s": 5, "topics": []}).interrupted is None  # an older backend: not said
