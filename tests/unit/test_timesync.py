"""Host time-sync status: parsing of chronyc/timedatectl/adjtimex outputs and the probes' order (pure)."""

import pytest

from arbiter_core.timesync import (
    CHRONY_COMMAND,
    TIMEDATECTL_COMMAND,
    Adjtimex,
    TimeSync,
    from_adjtimex,
    one_way_bound_ms,
    parse_chronyc_tracking,
    parse_timedatectl_show,
    probe,
)

# `chronyc -c tracking` (chrony 4.x field order: ref id, name, stratum, ref time, system time, last offset,
# rms offset, frequency, residual freq, skew, root delay, root dispersion, update interval, leap status)
CHRONY_SYNCED = (
    "A29FC87B,ntp1.example.net,3,1764000000.123456789,0.000012000,-0.000003000,0.000021000,"
    "-12.345,-0.001,0.012,0.001200000,0.000300000,64.5,Normal\n"
)
CHRONY_UNSYNCED = "00000000,,0,0.000000000,0.000000000,0.000000000,0.000000000,0.000,0.000,0.000,1.000000000,1.000000000,0.0,Not synchronised\n"  # noqa: E501
TIMEDATECTL = (
    "Timezone=Etc/UTC\nLocalRTC=no\nCanNTP=yes\nNTP=yes\nNTPSynchronized=yes\nTimeUSec=Tue 2026-11-24\n"
)
# adjtimex(2) read on this project's CI container: TIME_ERROR, STA_UNSYNC, 16 s errors
KERNEL_UNSYNCED = Adjtimex(state=5, status=0x40, maxerror_us=16_000_000, esterror_us=16_000_000)
KERNEL_SYNCED = Adjtimex(state=0, status=0x2001, maxerror_us=12_500, esterror_us=350)


def test_chrony_synchronised_with_its_own_error_rule():
    t = parse_chronyc_tracking(CHRONY_SYNCED)
    assert (t.source, t.synchronised, t.stratum, t.reference) == ("chrony", True, 3, "ntp1.example.net")
    assert t.offset_ms == pytest.approx(-0.012)  # 12 µs slow: clock minus true time is negative
    assert t.error_ms == pytest.approx(0.012 + 0.3 + 0.6)  # |offset| + root dispersion + root delay / 2


def test_chrony_not_synchronised_and_garbage():
    t = parse_chronyc_tracking(CHRONY_UNSYNCED)
    assert t.synchronised is False and "Not synchronised" in t.detail
    assert parse_chronyc_tracking("506 Cannot talk to daemon\n") is None
    assert parse_chronyc_tracking("") is None


def test_timedatectl_and_the_kernel():
    assert parse_timedatectl_show(TIMEDATECTL) == TimeSync("timesyncd", True)
    assert parse_timedatectl_show("Failed to connect to bus: Host is down") is None
    k = from_adjtimex(KERNEL_UNSYNCED)
    assert (k.source, k.synchronised, k.error_ms, k.max_error_ms) == ("adjtimex", False, 16000.0, 16000.0)
    assert from_adjtimex(KERNEL_SYNCED).synchronised is True and from_adjtimex(KERNEL_SYNCED).error_ms == 0.35


def test_probes_in_order_and_missing_tools_are_unknown_never_an_error():
    def runner(outputs):
        return lambda cmd: outputs.get(cmd)

    assert probe(runner({CHRONY_COMMAND: CHRONY_SYNCED}), lambda: KERNEL_UNSYNCED).source == "chrony"
    t = probe(runner({TIMEDATECTL_COMMAND: TIMEDATECTL}), lambda: KERNEL_SYNCED)
    assert (t.source, t.synchronised, t.error_ms) == ("timesyncd", True, 0.35)
    assert probe(runner({}), lambda: KERNEL_UNSYNCED).source == "adjtimex"
    t = probe(runner({}), lambda: None)
    assert t.source == "unknown" and t.synchronised is None


def test_the_health_block_round_trips_and_the_two_host_bound():
    t = parse_chronyc_tracking(CHRONY_SYNCED)
    assert TimeSync.from_obj(t.to_dict()) == t
    assert TimeSync.from_obj(None) is None and TimeSync.from_obj({"source": "ntpd"}) is None
    k = from_adjtimex(KERNEL_SYNCED)
    assert one_way_bound_ms(t, k) == pytest.approx(0.912 + 0.35)
    assert one_way_bound_ms(t, from_adjtimex(KERNEL_UNSYNCED)) is None
    assert one_way_bound_ms(t, TimeSync("timesyncd", True)) is None  # no error known: no bound
