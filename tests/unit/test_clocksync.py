"""Round trip, NTP offset, loss and negative latency from the sender's side (pure)."""

import pytest

from arbiter_core.record import LatencyRecord
from arbiter_tui.latency.clocksync import LatencyMeter


def report(seq, stamp_ms, raw_ms):
    return LatencyRecord(raw_ms, 0.0, 0.0, (stamp_ms + raw_ms) / 1000.0, "native", seq=seq)


def exchange(meter, seq, mono, stamp_ms, offset_ms, up_ms, down_ms):
    """One command over a path with the given one-way delays; the tracker's clock is offset."""
    meter.on_send(seq, stamp_ms, mono)
    raw = up_ms + offset_ms  # tracker receive (its clock) minus our stamp
    return meter.on_report(report(seq, stamp_ms, round(raw, 4)), mono + (up_ms + down_ms) / 1000.0)


def test_offset_comes_from_the_lowest_rtt_sample_and_its_bound_holds():
    m = LatencyMeter()
    true_offset = 7.0  # tracker clock 7 ms ahead: the raw one-way figure is inflated by 7 ms
    delays = [(0.4, 0.4), (2.0, 0.3), (0.15, 0.2), (5.0, 1.0), (0.3, 0.9)]
    for i, (up, down) in enumerate(delays):
        exchange(m, i, 100.0 + i, 1_800_000_000_000.0 + i * 10, true_offset, up, down)
    est = m.offset()
    # the best sample (rtt 0.35 ms): offset = raw - rtt/2 = 7.15 - 0.175
    assert est.rtt_ms == pytest.approx(0.35)
    assert est.offset_ms == pytest.approx(6.975)
    assert abs(est.offset_ms - true_offset) <= est.uncertainty_ms
    s = m.summary()
    assert s.raw_p50_ms == pytest.approx(7.4)  # the seed's figure keeps the offset
    # each sample is corrected with the best estimate at its arrival (live, not hindsight)
    assert s.corrected_p50_ms == pytest.approx(0.4)
    assert s.rtt_p50_ms == pytest.approx(1.2) and s.matched == 5 and s.negative == 0


def test_negative_raw_latencies_are_kept_and_counted():
    m = LatencyMeter()
    for i in range(4):
        exchange(m, i, 10.0 + i, 1e12 + i, offset_ms=-3.0, up_ms=0.2, down_ms=0.2)
    s = m.summary()
    assert s.negative == 4 and s.raw_p50_ms == pytest.approx(-2.8)
    assert s.corrected_p50_ms == pytest.approx(0.2)


def test_reports_not_ours_are_ignored_and_counted():
    m = LatencyMeter()
    m.on_send(1, 1000.0, 5.0)
    assert m.on_report(report(1, 2000.0, 0.3), 5.001) is None  # same seq, another console's stamp
    assert m.on_report(report(99, 1000.0, 0.3), 5.001) is None
    seed_record = LatencyRecord.from_obj(  # a seed tracker's record has no seq
        {"latency_ms": 1, "linear_x": 0.1, "angular_z": 0, "timestamp": 1.001, "deploy_mode": "native"}
    )
    assert m.on_report(seed_record, 5.0) is None
    assert m.foreign == 2 and m.matched == 0
    assert m.on_report(report(1, 1000.0, 0.3), 5.001) is not None


def test_unreported_commands_are_lost_per_window_and_on_disconnect():
    m = LatencyMeter(lost_after_s=1.0, loss_window_s=10.0)
    for i in range(5):
        m.on_send(i, 1000.0 + i, 100.0 + i * 0.1)
    m.on_report(report(0, 1000.0, 0.2), 100.01)
    assert m.expire(100.5) == 0
    assert m.expire(101.25) == 2  # sent at 100.1 and 100.2
    assert m.lost == 2 and m.lost_in_window() == 2
    m.reset_pending(101.3)  # the link dropped: the rest can never be reported
    assert m.lost == 4 and m.summary().in_flight == 0
    m.expire(115.0)
    assert m.lost_in_window() == 0 and m.lost == 4  # the window forgets, the total does not
