"""The latency screen's console line: every corrected figure with its interval, the clock model's drift,
the warning before drift carries the offset over --offset-warn-ms, and both hosts' time sync."""

from arbiter_core.record import LatencyRecord
from arbiter_core.timesync import TimeSync
from arbiter_tui.latency.clocksync import LatencyMeter
from arbiter_tui.session.views import LatencySnapshot
from arbiter_tui.shell.widgets.text import ClientLine


def drifting_meter(offset_ms, drift_ppm, seconds=40, up_ms=0.4, down_ms=0.4):
    m = LatencyMeter()
    for i in range(int(seconds * 10)):
        mono, stamp = 100.0 + i / 10, 1_800_000_000_000.0 + i * 100.0
        raw = round(up_ms + offset_ms + drift_ppm * 1e-3 * i / 10, 4)
        t1 = stamp + raw
        m.on_send(i, stamp, mono)
        record = LatencyRecord(raw, 0.0, 0.0, t1 / 1000, "native", seq=i, t_recv_ms=t1, t_sent_ms=t1 + 0.05)
        m.on_report(record, mono + (up_ms + 0.05 + down_ms) / 1000)
    return m


def line(meter, **kw):
    w = ClientLine()
    w.view = LatencySnapshot(link_state="CONNECTED", meter=meter.summary(), **kw)
    return w.draw().plain


def test_drift_is_shown_and_warned_before_the_offset_crosses_the_threshold():
    text = line(drifting_meter(-20.0, 500.0))  # -20 ms, +0.5 ms/s: at 40 s it is 0, crossing 10 ms at ~60 s
    assert "clock -0.1 ms ± 0.4 ms, drifting +500 ppm (30 ms/min)" in text  # at the last exchange, 39.9 s
    assert "CLOCK DRIFT: offset crosses 10 ms in ~20 s" in text
    # by round trips alone the asymmetry is unknown: 0.4 ms each way, or all 0.8 ms one way
    assert "one-way corrected p50 0.400 ms [0.000, 0.800]" in text


def test_both_hosts_synchronised_bound_the_figures_unless_the_offset_contradicts_them():
    synced = TimeSync("chrony", True, error_ms=0.5)
    text = line(drifting_meter(3.0, 0.0), local_sync=synced, robot_sync=synced, host_bound_ms=1.0,
                sync_contradicted=True)  # fmt: skip
    assert (
        "time sync: this host chrony synchronised ±0.50 ms, robot host chrony synchronised ±0.50 ms" in text
    )
    assert "CONTRADICTED by the measured offset" in text
    text = line(drifting_meter(0.0, 0.0), local_sync=synced, robot_sync=None)
    assert "robot host not said" in text and "CLOCK" not in text
