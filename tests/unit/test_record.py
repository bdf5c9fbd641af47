"""LatencyRecord: the tracker builds it, the API and /latency_report carry its JSON, the console parses it."""

import json
import math

import pytest

from arbiter_backend.tracker import LatencyTracker
from arbiter_core import envelope
from arbiter_core.listening import format_listening, parse_listening
from arbiter_core.record import LatencyRecord, RecordError

T0 = 1_800_000_000_000_000_000


def test_the_tracker_report_is_the_seed_json_and_parses_back_to_the_same_record():
    tracker = LatencyTracker(clock_ns=lambda: T0 + 37_123)  # the report leaves 37.123 µs after arrival
    accepted = tracker.on_stamped(envelope.build(0.3, -0.2, seq=7, clock_ns=lambda: T0 - 1_500_000), T0)
    obj = json.loads(accepted.text)
    assert list(obj) == ["latency_ms", "linear_x", "angular_z", "timestamp", "deploy_mode", "seq", "rx_seq",
                         "t_recv_ms", "t_sent_ms"]  # fmt: skip
    assert obj == {"latency_ms": 1.5, "linear_x": 0.3, "angular_z": -0.2, "timestamp": T0 / 1e9,
                   "deploy_mode": "native", "seq": 7, "rx_seq": 1,
                   "t_recv_ms": T0 / 1e6, "t_sent_ms": T0 / 1e6 + 0.037}  # fmt: skip
    assert LatencyRecord.from_json(accepted.text) == accepted.record
    # the API serves the same text it published
    assert tracker.latency_response()["records"] == [obj]


def test_the_ntp_stamps_are_optional_and_checked():
    seed = {"latency_ms": 2, "linear_x": 0, "angular_z": 0.5, "timestamp": 1.0, "deploy_mode": "pi"}
    assert LatencyRecord.from_obj(seed).t_recv_ms is None
    full = LatencyRecord.from_obj({**seed, "t_recv_ms": 1000.0, "t_sent_ms": 1000.25})
    assert (full.t_recv_ms, full.t_sent_ms) == (1000.0, 1000.25)
    with pytest.raises(RecordError, match="t_sent_ms"):
        LatencyRecord.from_obj({**seed, "t_recv_ms": 1000.0, "t_sent_ms": "x"})


def test_a_stale_record_says_so_and_a_seed_record_has_only_the_five_fields():
    tracker = LatencyTracker(clock_ns=lambda: T0)
    old = envelope.build(0.3, 0.0, clock_ns=lambda: T0 - 2_000_000_000)
    accepted = tracker.on_stamped(old, T0)
    assert accepted.stale and json.loads(accepted.text)["stale"] is True
    seed = {"latency_ms": 2, "linear_x": 0, "angular_z": 0.5, "timestamp": 1.0, "deploy_mode": "pi"}
    record = LatencyRecord.from_obj(seed)
    assert (record.seq, record.rx_seq, record.stale) == (None, None, False)
    assert record.to_dict() == {**seed, "latency_ms": 2.0, "linear_x": 0.0}


@pytest.mark.parametrize(
    ("obj", "field"),
    [
        ([], "object"),
        ({"linear_x": 0, "angular_z": 0, "timestamp": 1, "deploy_mode": "x"}, "latency_ms"),
        (
            {"latency_ms": "1", "linear_x": 0, "angular_z": 0, "timestamp": 1, "deploy_mode": "x"},
            "latency_ms",
        ),
        (
            {"latency_ms": math.nan, "linear_x": 0, "angular_z": 0, "timestamp": 1, "deploy_mode": "x"},
            "latency_ms",
        ),
        ({"latency_ms": 1, "linear_x": True, "angular_z": 0, "timestamp": 1, "deploy_mode": "x"}, "linear_x"),
        ({"latency_ms": 1, "linear_x": 0, "angular_z": 0, "timestamp": 1, "deploy_mode": 3}, "deploy_mode"),
        (
            {"latency_ms": 1, "linear_x": 0, "angular_z": 0, "timestamp": 1, "deploy_mode": "x", "seq": -1},
            "seq",
        ),
        (
            {
                "latency_ms": 1,
                "linear_x": 0,
                "angular_z": 0,
                "timestamp": 1,
                "deploy_mode": "x",
                "rx_seq": 1.5,
            },
            "rx_seq",
        ),
        (
            {"latency_ms": 1, "linear_x": 0, "angular_z": 0, "timestamp": 1, "deploy_mode": "x", "stale": 1},
            "stale",
        ),
    ],
)
def test_a_record_of_the_wrong_shape_names_the_field(obj, field):
    with pytest.raises(RecordError, match=field):
        LatencyRecord.from_obj(obj)


def test_not_json_is_a_record_error():
    with pytest.raises(RecordError, match="not JSON"):
        LatencyRecord.from_json("{nope")


def test_the_listening_line_round_trips_with_and_without_the_bridge():
    line = format_listening("127.0.0.1", 9090, 8085, deploy_mode="pi", sim="on")
    found = parse_listening("noise before " + line + "\n")
    assert (found.host, found.bridge_port, found.api_port) == ("127.0.0.1", 9090, 8085)
    assert found.extra("deploy_mode") == "pi" and found.extra("sim") == "on"
    found = parse_listening(format_listening("::1", None, 0))
    assert (found.host, found.bridge_port, found.api_port) == ("::1", None, 0)
    assert parse_listening("arbiter-backend: WARNING something") is None
    assert parse_listening("arbiter-backend listening: api=ftp://x:1") is None


def test_the_tracker_stats_block_reads_back_as_the_summary_it_was_made_from():
    from arbiter_core.record import latency_stats, parse_latency_stats
    from arbiter_core.stats import summarize

    values = [0.31, 0.2, 0.45, 0.33, 0.29]
    back = parse_latency_stats(latency_stats(values))
    want = summarize(values)
    assert back.count == want.count == 5
    for name in ("mean", "min", "max", "p95", "stddev"):
        assert getattr(back, name) == pytest.approx(getattr(want, name), abs=1e-4)
    assert parse_latency_stats(latency_stats([])).count == 0


@pytest.mark.parametrize(
    "block, field",
    [
        ([], "object"),
        ({"count": "3"}, "stats.count"),
        ({"count": -1}, "stats.count"),
        ({"count": True}, "stats.count"),
        ({"count": 2, "mean_ms": 1, "min_ms": 1, "max_ms": 1, "p95_ms": "x", "stddev_ms": 0}, "stats.p95_ms"),
        (
            {"count": 2, "mean_ms": float("nan"), "min_ms": 1, "max_ms": 1, "p95_ms": 1, "stddev_ms": 0},
            "stats.mean_ms",
        ),
        ({"count": 2, "mean_ms": 1, "min_ms": 1, "max_ms": 1, "p95_ms": 1}, "stats.stddev_ms"),
    ],
)
def test_a_malformed_stats_block_is_refused_naming_the_field(block, field):
    from arbiter_core.record import RecordError, parse_latency_stats

    with pytest.raises(RecordError, match=field):
        parse_latency_stats(block)
