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
    # every sample is corrected with the clock model as it is now (here: the best exchange's offset, a
    # 4 s span is too short for a drift), so each one-way figure is 0.025 ms over its true delay...
    assert s.corrected_p50_ms == pytest.approx(0.425)
    # ...and its interval holds it: [corrected - bound, corrected + bound], inside [0, delay]
    assert s.corrected_p50_lo_ms <= 0.4 <= s.corrected_p50_hi_ms
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


def ntp_report(seq, stamp_ms, raw_ms, held_ms):
    t1 = stamp_ms + raw_ms
    return LatencyRecord(raw_ms, 0.0, 0.0, t1 / 1000.0, "native", seq=seq,
                         t_recv_ms=t1, t_sent_ms=t1 + held_ms)  # fmt: skip


def run(meter, seconds, *, offset_ms, drift_ppm=0.0, up_ms, down_ms, held_ms=0.0, rate_hz=10.0):
    """Commands at rate_hz; our wall stamp and monotonic clock advance together; the tracker's clock is
    offset and drifts; it holds each command held_ms before it reports."""
    n = int(seconds * rate_hz)
    for i in range(n):
        mono = 100.0 + i / rate_hz
        stamp = 1_800_000_000_000.0 + i * 1000.0 / rate_hz
        offset = offset_ms + drift_ppm * 1e-3 * (mono - 100.0)
        raw = round(up_ms + offset, 4)
        meter.on_send(i, stamp, mono)
        meter.on_report(ntp_report(i, stamp, raw, held_ms), mono + (up_ms + held_ms + down_ms) / 1000.0)
    return 100.0 + n / rate_hz


def test_the_trackers_own_time_enters_neither_the_offset_nor_the_one_way_figure():
    m = LatencyMeter()
    run(m, 3, offset_ms=250.0, up_ms=0.3, down_ms=0.3, held_ms=4.0)  # a tracker that takes 4 ms to report
    s = m.summary()
    assert s.offset.offset_ms == pytest.approx(250.0, abs=0.01) and s.offset.rtt_ms == pytest.approx(0.6)
    assert s.corrected_p50_ms == pytest.approx(0.3, abs=0.01)
    assert s.rtt_p50_ms == pytest.approx(4.6)  # the round trip as measured still holds it


def test_under_drift_the_corrected_one_way_stays_right_and_drift_is_not_jitter():
    m = LatencyMeter()
    end = run(m, 40, offset_ms=-1500.0, drift_ppm=500.0, up_ms=0.5, down_ms=0.5)
    s = m.summary(at_mono=end)
    assert s.offset.drift_ppm == pytest.approx(500.0, abs=20.0)
    assert s.corrected_p50_ms == pytest.approx(0.5, abs=0.05) and s.jitter_ms < 0.05
    assert s.corrected_p50_lo_ms <= 0.5 <= s.corrected_p50_hi_ms
    assert s.offset.offset_ms == pytest.approx(-1500.0 + 0.5 * 40, abs=0.2)


def test_asymmetric_paths_the_one_way_interval_holds_the_truth_and_host_sync_can_tighten_it():
    m = LatencyMeter()
    run(m, 10, offset_ms=250.0, up_ms=20.0, down_ms=5.0)
    s = m.summary()
    # no round trip can tell 20/5 from 12.5/12.5
    assert s.corrected_p50_ms == pytest.approx(12.5, abs=0.05)
    assert s.corrected_p50_lo_ms <= 20.0 <= s.corrected_p50_hi_ms
    assert s.corrected_p50_lo_ms >= 0.0 and s.corrected_p50_hi_ms <= 25.0 + 1e-6
    # clocks in step (offset 0) on hosts that say so, to within 1 ms together: raw ± 1 ms
    m = LatencyMeter()
    run(m, 10, offset_ms=0.0, up_ms=20.0, down_ms=5.0)
    s = m.summary(host_error_ms=1.0)
    assert s.host_bound_used
    assert (s.corrected_p50_lo_ms, s.corrected_p50_hi_ms) == pytest.approx((19.0, 21.0))
