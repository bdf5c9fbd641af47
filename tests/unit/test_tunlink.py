"""The Wi-Fi link's impairments (``tests/support/tunlink.py``), one direction, without devices."""

import random
import statistics

import pytest

from tests.support.tunlink import Impairment, _Direction, tcp_seq_end, unique_subnet


def test_jitter_delays_by_its_spread_and_never_reorders():
    d = _Direction(Impairment(delay_s=0.030, jitter_s=0.020), random.Random(1))
    sent = [i / 30.0 for i in range(3000)]  # 30 packets a second, as a held key's repeats
    due = [d.due(t) for t in sent]
    assert due == sorted(due)  # FIFO: a packet never leaves before the one ahead of it
    delays = [b - a for a, b in zip(sent, due, strict=True)]
    assert min(delays) >= 0.0
    assert statistics.mean(delays) == pytest.approx(0.031, abs=0.003)  # a little over 30: FIFO waits
    assert max(delays) > 0.07  # the tail a normal spread of 20 ms gives


def test_burst_loss_keeps_its_mean_and_comes_in_runs():
    n = 200_000
    bursty = _Direction(Impairment(loss=0.03, burst=4.0), random.Random(2))
    lost = [bursty.lost() for _ in range(n)]
    assert sum(lost) / n == pytest.approx(0.03, rel=0.1)
    runs = [len(r) for r in "".join("x" if x else "." for x in lost).split(".") if r]
    assert statistics.mean(runs) == pytest.approx(4.0, rel=0.1)
    plain = _Direction(Impairment(loss=0.03), random.Random(2))
    lost = [plain.lost() for _ in range(n)]
    runs = [len(r) for r in "".join("x" if x else "." for x in lost).split(".") if r]
    assert sum(lost) / n == pytest.approx(0.03, rel=0.1) and statistics.mean(runs) < 1.1


def test_the_rate_limit_paces_a_burst_and_drops_beyond_its_buffer():
    d = _Direction(Impairment(rate_bps=256_000, queue_s=2.0), random.Random(3))
    departures = [d.departure(0.0, 1000) for _ in range(100)]  # 100 kB at once: 3.1 s at 32 kB/s
    sent = [t for t in departures if t is not None]
    assert sent[2] == 0.0 < sent[3]  # the bucket's 3000 B go at once, then 1000 B every 31 ms
    assert sent[-1] == pytest.approx(2.0, abs=0.04)  # queued up to the 2 s buffer...
    assert departures.count(None) == 100 - len(sent) > 30  # ...the tail beyond it dropped
    assert (len(sent) - 3) * 1000 / sent[-1] == pytest.approx(32_000, rel=0.02)


def test_a_tcp_segments_sequence_end_and_none_without_data():
    ip = bytes([0x45, 0, 0, 40 + 36]) + bytes(5) + bytes([6]) + bytes(10)
    tcp = (1000).to_bytes(4, "big").rjust(8, b"\0") + bytes(4) + bytes([5 << 4]) + bytes(7)
    assert tcp_seq_end(ip + tcp + bytes(36)) == 1036
    ack = bytes([0x45, 0, 0, 40]) + ip[4:]
    assert tcp_seq_end(ack + tcp) is None


def test_subnets_differ_per_process_and_link():
    assert unique_subnet("123x0") != unique_subnet("123x1") != unique_subnet("124x0")
    host, ns = unique_subnet("4194303x7")
    assert host.startswith("10.") and all(0 <= int(p) <= 255 for p in ns.split("."))
