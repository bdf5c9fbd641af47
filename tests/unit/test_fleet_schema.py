"""The fleet wire schema (arbiter_core.fleet): what a robot may send, what a console refuses, in one line."""

import contextlib
import json
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from arbiter_core import fleet
from arbiter_core.fleet import FleetPayloadError
from arbiter_core.topicstats import Expectation, TopicFigures

T = 1_800_000_000.0


def status(**kw):
    base = dict(
        robot="r1",
        t=T,
        started=T - 60,
        driver="console",
        mode="embedded, sim",
        rosbridge="ws://lab-r1:9090",
        tracker="http://lab-r1:8085",
        pose=(1.0, -2.0, 0.5),
    )
    return fleet.Status(**{**base, **kw})


def payloads():
    grade = fleet.RunGrade(3, "pure_pursuit", "square", "completed", 41.25, 4, 4, 0.08, T - 5)
    return [
        status(),
        fleet.Latency(
            "r1",
            T,
            count=120,
            total=900,
            p50_ms=1.5,
            p95_ms=3.25,
            max_ms=9.0,
            sync_source="chrony",
            sync_ok=True,
            sync_error_ms=0.4,
        ),
        fleet.Topics(
            "r1",
            T,
            5.0,
            2,
            (
                fleet.TopicHealth("/scan", "silent", None, 4000.0),
                fleet.TopicHealth("/odom", "ok", 50.0, 20.0, 45.0),
            ),
        ),
        fleet.Runs("r1", T, 3, grade),
    ]


@pytest.mark.parametrize("p", payloads(), ids=lambda p: p.kind)
def test_every_payload_round_trips_and_fits_its_limit(p):
    data = fleet.encode(p)
    assert len(data) <= fleet.MAX_BYTES[p.kind]
    assert fleet.decode(data, p.kind, "r1") == p
    obj = json.loads(data)
    assert (obj["v"], obj["kind"], obj["robot"]) == (fleet.VERSION, p.kind, "r1")


def test_the_stated_bound_is_each_kinds_limit_over_its_period():
    assert round(1536 / 1 + 768 / 2 + 4096 / 5 + 1024 / 5) == fleet.BOUND_BYTES_PER_S
    assert fleet.BOUND_BYTES_PER_S < 3000


GOOD = fleet.encode(status())


@pytest.mark.parametrize(
    ("data", "words"),
    [
        (b"not json at all", "status: not JSON"),
        (b"\xff\xfe\x00", "status: not UTF-8"),
        (b"[1, 2]", "a JSON list, not an object"),
        (GOOD.replace(b'"v":1', b'"v":2'), "schema version 2, this console reads version 1"),
        (GOOD.replace(b'"v":1', b'"v":true'), "schema version True"),
        (GOOD.replace(b'"t":1800000000.0', b'"t":NaN'), "NaN (numbers must be finite)"),
        (GOOD.replace(b'"t":1800000000.0', b'"t":-Infinity'), "-Infinity"),
        (GOOD.replace(b'"robot":"r1"', b'"robot":"r2"'), "names robot 'r2' on r1's key"),
        (GOOD.replace(b'"kind":"status"', b'"kind":"latency"'), "says kind 'latency'"),
        (GOOD.replace(b'"driver":"console"', b'"driver":"martian"'), "status.driver must be one of"),
        (GOOD.replace(b'"rosbridge":"ws://lab-r1:9090"', b'"rosbridge":"http://x"'), "status.rosbridge"),
        (GOOD.replace(b'"started":', b'"started_":'), "status.started is missing"),
        (
            GOOD.replace(b'"pose":[1.0,-2.0,0.5]', b'"pose":[1.0,"x",0.5]'),
            "status.pose[1] must be a finite number",
        ),
        (GOOD.replace(b'"runs":0', b'"runs":-1'), "status.runs must be a whole number"),
        (b"x" * 10_000_000, "status: 10.0 MB, over the 1.5 kB a status may be"),
        (b"[" * 1400 + b"]" * 1400, "status:"),
    ],
    ids=[
        "not-json",
        "not-utf8",
        "list",
        "version-2",
        "version-bool",
        "nan",
        "infinity",
        "other-robot",
        "other-kind",
        "bad-enum",
        "bad-url",
        "missing",
        "bad-pose",
        "negative",
        "10MB",
        "deep",
    ],
)
def test_a_bad_payload_is_one_line_naming_what_is_wrong(data, words):
    with pytest.raises(FleetPayloadError) as exc:
        fleet.decode(data, "status", "r1")
    text = str(exc.value)
    assert words in text
    assert "\n" not in text and len(text) < 240


def test_topics_must_come_worst_first():
    t = fleet.Topics(
        "r1", T, 5.0, 2, (fleet.TopicHealth("/odom", "ok"), fleet.TopicHealth("/scan", "silent"))
    )
    with pytest.raises(ValueError, match="sorted worst first"):
        fleet.encode(t)


def test_the_largest_status_the_schema_allows_fits_its_limit():
    big = status(
        robot="x" * 63,
        driver_detail="d" * 120,
        controller="c" * 40,
        mission="m" * 40,
        run_state="r" * 40,
        mode="m" * 40,
        waypoint=2**52,
        waypoints=2**52,
        runs=2**52,
        pose=(-1.2345678901234567e300,) * 3,
        velocity=(-1.2345678901234567e300,) * 2,
        rosbridge="wss://" + "h" * 194,
        tracker="https://" + "h" * 192,
        namespace="/" + "n" * 119,
    )
    assert len(fleet.encode(big)) <= fleet.MAX_BYTES["status"]


def test_the_publisher_refuses_what_a_console_would():
    many = tuple(
        fleet.TopicHealth("/" + "t" * 119, "ok", 1e300, 1e300, 1e300) for _ in range(fleet.MAX_TOPICS)
    )
    with pytest.raises(ValueError, match=r"topics payload of .* bytes is over its 4096-byte limit"):
        fleet.encode(fleet.Topics("r1", T, 5.0, 40, many))
    with pytest.raises(ValueError):
        fleet.encode(status(pose=(math.nan, 0.0, 0.0)))
    with pytest.raises(FleetPayloadError, match="printable string of 1 to 40"):
        fleet.encode(status(mode="two\nlines"))


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=2000))
def test_any_bytes_are_a_payload_or_one_fleet_error(data):
    for kind in (*fleet.KINDS, fleet.HISTORY):
        with contextlib.suppress(FleetPayloadError):
            fleet.decode(data, kind, "r1")


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=20),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=10), inner, max_size=5),
    max_leaves=20,
)


@settings(max_examples=300, deadline=None)
@given(json_values, st.sampled_from([*fleet.KINDS, fleet.HISTORY, fleet.STOP]))
def test_any_json_with_the_right_header_is_a_payload_or_one_fleet_error(body, kind):
    obj = {"v": 1, "kind": kind, "robot": "r1", **(body if isinstance(body, dict) else {"x": body})}
    with contextlib.suppress(FleetPayloadError):
        fleet.decode_obj(obj, kind, "r1")


def test_a_stop_answer_round_trips_and_says_what_the_robot_did_in_one_line():
    cancel = fleet.StopCancel("/navigate_to_pose", "cancelled", 1)
    answer = fleet.StopAnswer("r1", T, "robot", True, "stanley on square at 2/4", 0, (cancel,))
    data = fleet.encode(answer)
    assert len(data) <= fleet.MAX_BYTES[fleet.STOP] and fleet.decode(data, fleet.STOP, "r1") == answer
    words = "stopped: stanley aborted, 0 commands, 1 goal of /navigate_to_pose cancelled, zero sent"
    assert answer.words() == words
    idle = fleet.StopAnswer("r1", T, "nobody", True)
    assert idle.words() == "stopped: nothing was driving, zero sent"
    driven = fleet.StopAnswer("r1", T, "console", True, still="a console drives (last command 40 ms ago)")
    assert driven.words() == "asked: zero sent; still: a console drives (last command 40 ms ago)"
    failed = fleet.StopAnswer("r1", T, "foreign", False, cancels=(fleet.StopCancel("/spin", "failed"),))
    assert failed.words() == "asked: /spin not cancelled"
    pending = fleet.StopAnswer("r1", T, "foreign", True, cancels=(fleet.StopCancel("/spin", "pending"),))
    assert fleet.decode(fleet.encode(pending), fleet.STOP, "r1") == pending  # a cancel still under way
    assert pending.words().startswith("asked: /spin cancel pending, zero sent")
    bad = json.loads(data)
    bad["cancels"][0]["outcome"] = "maybe"
    with pytest.raises(FleetPayloadError, match=r"stop.cancels\[0\].outcome must be one of cancelled"):
        fleet.decode(json.dumps(bad).encode(), fleet.STOP, "r1")


def test_history_holds_payloads_checked_as_they_were():
    h = fleet.History("r1", T, 2.0, tuple(payloads()))
    back = fleet.decode(fleet.encode(h), fleet.HISTORY, "r1")
    assert back == h
    bad = json.loads(fleet.encode(h))
    bad["entries"][1]["p95_ms"] = "fast"
    with pytest.raises(
        FleetPayloadError, match=r"history.entries\[1\]: latency.p95_ms must be a finite number"
    ):
        fleet.decode(json.dumps(bad).encode(), fleet.HISTORY, "r1")


@pytest.mark.parametrize(
    ("parameters", "minutes"),
    [
        ("", 10.0),
        ("minutes=2", 2.0),
        ("minutes=1e9", 10.0),
        ("minutes=-3", 0.0),
        ("minutes=nan", 10.0),
        ("minutes=x", 10.0),
        ("a=1;minutes=0.5", 0.5),
    ],
)
def test_history_minutes_are_bounded(parameters, minutes):
    assert fleet.history_minutes(parameters) == minutes


def test_names_are_one_key_chunk():
    assert fleet.robot_name("lab-r1.b_2") == "lab-r1.b_2"
    for bad in ("", "a/b", "*", "**", "r$1", "-r1", "a b", "x" * 64, "@admin"):
        with pytest.raises(ValueError, match="is not one key chunk"):
            fleet.robot_name(bad)
    assert fleet.default_name("/site/robot1", "ignored") == "site.robot1"
    assert fleet.default_name("", "turtle-7.lab.example.org") == "turtle-7"
    assert fleet.default_name("", "__") == "robot"
    assert fleet.parse_key("arbiter/r1/status") == ("r1", "status")
    assert fleet.parse_key("arbiter/r1/x/status") is None
    assert fleet.parse_key("other/r1/status") is None


def test_endpoints_name_the_bad_one():
    assert fleet.parse_endpoints("tcp/10.0.0.5:7447, tls/router.lan:7447") == (
        "tcp/10.0.0.5:7447",
        "tls/router.lan:7447",
    )
    with pytest.raises(ValueError, match=r"'10\.0\.0\.5:7447' is not a Zenoh endpoint"):
        fleet.parse_endpoints("10.0.0.5:7447")
    with pytest.raises(ValueError, match="'http/x:1' is not a Zenoh endpoint"):
        fleet.parse_endpoints("http/x:1")
    with pytest.raises(ValueError, match="no endpoint given"):
        fleet.parse_endpoints(" , ")


def fig(name, state="ok", rate=None):
    return TopicFigures(name=name, type="t", state=state, rate_hz=rate, age_ms=10.0)


def test_topics_payload_judges_against_expectations_and_puts_the_worst_first():
    figs = [
        fig("/odom", rate=31.0),
        fig("/scan", "silent"),
        fig("/cmd_vel", "quiet"),
        fig("/imu", rate=100.0),
    ]
    p = fleet.topics_payload("r1", T, 5.0, figs, [Expectation("/odom", 45.0), Expectation("/map", 1.0)])
    assert [(t.name, t.health) for t in p.topics] == [
        ("/map", "missing"),
        ("/odom", "below"),
        ("/scan", "silent"),
        ("/cmd_vel", "quiet"),
        ("/imu", "ok"),
    ]
    assert p.worst.words() == "/map missing"
    assert p.topics[1].words() == "/odom 31<45 Hz"
    fleet.encode(p)


def test_topics_payload_keeps_the_worst_that_fit_and_counts_them_all():
    figs = [fig(f"/camera_{i:03d}/image_raw/compressed/with/a/long/name", rate=30.0) for i in range(200)]
    figs[150] = fig(figs[150].name, "silent")
    p = fleet.topics_payload("r1", T, 5.0, figs, [])
    assert p.watched == 200
    assert 0 < len(p.topics) <= fleet.MAX_TOPICS
    assert p.topics[0].health == "silent"
    assert len(fleet.encode(p)) <= fleet.MAX_BYTES["topics"]


def test_while_the_robots_monitor_restarts_its_topics_are_unknown_not_silent_nor_below():
    figs = [fig("/odom", "unknown", rate=31.0), fig("/scan", "unknown"), fig("/imu", "unmeasured")]
    why = "monitor restarted: RuntimeError: boom\n" + "x" * 300  # cut to fit, made printable
    p = fleet.topics_payload("r1", T, 5.0, figs, [Expectation("/odom", 45.0)], why)
    assert [(t.name, t.health) for t in p.topics] == [
        ("/odom", "unknown"),
        ("/scan", "unknown"),
        ("/imu", "unmeasured"),
    ]
    assert p.monitor is not None and p.monitor.startswith("monitor restarted: RuntimeError: boom x")
    assert fleet.decode(fleet.encode(p), "topics", "r1") == p
    assert fleet.topics_payload("r1", T, 5.0, figs, []).monitor is None


def test_session_settings_retry_for_ever_and_turn_scouting_off_without_a_file():
    s = fleet.session_settings("client", ["tcp/10.0.0.1:7447"], (), 1500)
    assert s["connect/timeout_ms"] == -1
    assert s["transport/link/tx/lease"] == 1500
    assert s["scouting/multicast/enabled"] is False
    assert "scouting/multicast/enabled" not in fleet.session_settings("client", ["tcp/x:1"], own_file=True)


def test_a_robot_as_a_peer_listens_nowhere_unless_its_file_says():
    assert fleet.session_settings("peer", ["tcp/10.0.0.1:7447"])["listen/endpoints"] == []
    assert "listen/endpoints" not in fleet.session_settings("peer", ["tcp/10.0.0.1:7447"], own_file=True)
    assert fleet.session_settings("router", (), ["tcp/0.0.0.0:7447"])["listen/endpoints"] == [
        "tcp/0.0.0.0:7447"
    ]
