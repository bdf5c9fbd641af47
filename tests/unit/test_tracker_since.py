"""The tracker's receive counter, ``since`` paging and negative latencies (no I/O)."""

from arbiter_backend.tracker import LatencyTracker
from arbiter_core import envelope


def feed(tracker, n, start_ns=1_800_000_000_000_000_000, latency_ns=300_000):
    for i in range(n):
        send_ns = start_ns + i * 10_000_000
        text = envelope.build(0.1, 0.0, seq=i, clock_ns=lambda s=send_ns: s)
        assert tracker.on_stamped(text, send_ns + latency_ns) is not None


def test_since_returns_only_new_records_oldest_first_with_paging():
    t = LatencyTracker(max_records=50)
    feed(t, 30)
    body = t.latency_response(limit=10, since=0)
    assert [r["rx_seq"] for r in body["records"]] == list(range(1, 11))
    assert body["more"] is True and body["last_rx_seq"] == 30
    body = t.latency_response(limit=100, since=25)
    assert [r["rx_seq"] for r in body["records"]] == [26, 27, 28, 29, 30] and body["more"] is False
    assert t.latency_response(limit=100, since=30)["records"] == []
    assert t.latency_response(limit=100, since=10**9)["records"] == []
    # without since: the most recent, as the seed's API
    assert [r["rx_seq"] for r in t.latency_response(limit=3)["records"]] == [28, 29, 30]


def test_since_older_than_the_window_starts_at_the_oldest_kept():
    t = LatencyTracker(max_records=10)
    feed(t, 25)
    body = t.latency_response(limit=100, since=3)
    assert [r["rx_seq"] for r in body["records"]] == list(range(16, 26))
    assert body["dropped"] == 15 and body["window"] == 10


def test_negative_latencies_are_kept_and_counted_never_clipped():
    t = LatencyTracker()
    feed(t, 3, latency_ns=-2_500_000)  # the sender's clock runs 2.5 ms ahead
    feed(t, 2, start_ns=1_800_000_001_000_000_000)
    body = t.latency_response()
    assert body["negative"] == 3
    assert [r["latency_ms"] for r in body["records"]][:3] == [-2.5, -2.5, -2.5]
    assert body["stats"]["min_ms"] == -2.5
    assert t.health()["negative"] == 3
