"""Safety rules of the tracker as pure logic: stale commands, speed-up limits, the watchdog."""

import json
import math

import pytest

from arbiter_backend.tracker import LatencyTracker
from arbiter_core import envelope
from arbiter_core.kinematics import DEFAULT_LIMITS, Limits, limit_speedup

T0_NS = 1_750_000_000_000_000_000


class Clock:
    def __init__(self) -> None:
        self.mono = 100.0

    def __call__(self) -> float:
        return self.mono


def make(max_age: float = 300.0, limits: Limits = DEFAULT_LIMITS) -> tuple[LatencyTracker, Clock]:
    clock = Clock()
    return LatencyTracker(limits=limits, max_command_age_ms=max_age, monotonic=clock), clock


def cmd(v: float, w: float, age_ms: float, seq: int = 0, offset_ms: float | None = None) -> str:
    """An envelope stamped ``age_ms`` before T0 on the sender's clock."""
    return envelope.build(v, w, seq=seq, clock_ns=lambda: T0_NS - int(age_ms * 1e6), offset_ms=offset_ms)


@pytest.mark.parametrize(
    ("current", "target", "expected"),
    [
        (0.0, 1.0, 0.2),  # speeding up: at most a*dt
        (0.5, 0.6, 0.6),  # within one step
        (0.8, 0.1, 0.1),  # slowing down: at once
        (0.8, 0.0, 0.0),  # stopping: at once
        (0.8, -0.5, -0.2),  # reversing: stop at once, then speed up from rest
        (-0.3, -1.0, -0.5),
        (0.4, math.nan, 0.0),  # non-finite target: a stop
        (math.inf, 0.5, 0.2),  # a corrupt current value counts as rest
    ],
)
def test_limit_speedup(current, target, expected):
    assert limit_speedup(current, target, 2.0, 0.1) == pytest.approx(expected)


def test_fresh_commands_are_forwarded_clamped_and_ramped():
    t, clock = make()
    out = []
    for i in range(8):
        acc = t.on_stamped(cmd(5.0, -9.0, age_ms=1.0, seq=i), T0_NS)
        assert acc is not None and not acc.stale
        out.append(acc.forward)
        clock.mono += 0.05  # 20 Hz
    # first step assumes one 0.1 s period; then 0.05 s steps of 2 m/s² and 6 rad/s²; capped at the limits
    assert [v for v, _ in out] == pytest.approx([0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9])
    assert [w for _, w in out] == pytest.approx([-0.6, -0.9, -1.2, -1.5, -1.8, -2.0, -2.0, -2.0])
    stop = t.on_stamped(cmd(0.0, 0.0, age_ms=1.0, seq=9), T0_NS)
    assert stop is not None and stop.forward == (0.0, 0.0)  # slowing down is never delayed


def test_stale_command_is_recorded_reported_counted_and_never_forwarded():
    t, clock = make(max_age=300.0)
    assert t.on_stamped(cmd(0.5, 0.0, age_ms=400.0, seq=1), T0_NS).forward is None  # robot at rest
    moving = t.on_stamped(cmd(0.1, 0.0, age_ms=5.0, seq=2), T0_NS)
    assert moving is not None and moving.forward == (0.1, 0.0)
    clock.mono += 0.1
    stale = t.on_stamped(cmd(0.5, 0.3, age_ms=301.0, seq=3), T0_NS)
    assert stale is not None and stale.stale
    assert stale.forward == (0.0, 0.0)  # the robot was moving: one stop, not the stale command
    again = t.on_stamped(cmd(0.5, 0.3, age_ms=900.0, seq=4), T0_NS)
    assert again is not None and again.forward is None  # already stopped: nothing at all
    body = t.latency_response()
    assert body["stale"] == 3 and body["max_command_age_ms"] == 300.0
    assert [r.get("stale", False) for r in body["records"]] == [True, False, True, True]
    assert json.loads(stale.text)["latency_ms"] == 301.0
    assert t.health()["last_stale_age_ms"] == 900.0


def test_offset_estimate_decides_the_age_across_clocks():
    t, _ = make(max_age=300.0)
    # Sender's clock 2 s behind the tracker's: raw latency 2001 ms, offset estimate 2000 ms -> 1 ms old.
    fresh = t.on_stamped(cmd(0.1, 0.0, age_ms=2001.0, seq=1, offset_ms=2000.0), T0_NS)
    assert fresh is not None and not fresh.stale and fresh.forward == (0.1, 0.0)
    assert fresh.record.latency_ms == 2001.0  # the record keeps the seed's raw figure
    # Sender's clock 2 s ahead: raw -1500 ms but really 500 ms old.
    old = t.on_stamped(cmd(0.1, 0.0, age_ms=-1500.0, seq=2, offset_ms=-2000.0), T0_NS)
    assert old is not None and old.stale and old.forward == (0.0, 0.0)
    # Without an estimate the raw figure is all there is.
    assert t.on_stamped(cmd(0.1, 0.0, age_ms=2001.0, seq=3), T0_NS).stale


def test_max_age_zero_turns_the_check_off_and_watchdog_resets_the_ramp():
    t, clock = make(max_age=0.0)
    acc = t.on_stamped(cmd(1.0, 0.0, age_ms=10_000.0), T0_NS)
    assert acc is not None and not acc.stale and acc.forward == (0.2, 0.0)
    clock.mono += 0.05
    assert t.on_stamped(cmd(1.0, 0.0, age_ms=1.0), T0_NS).forward == pytest.approx((0.3, 0.0))
    clock.mono += 1.0
    assert t.watchdog_due()
    clock.mono += 5.0
    # after the watchdog stop the robot is at rest: the ramp starts from zero again
    assert t.on_stamped(cmd(1.0, 0.0, age_ms=1.0), T0_NS).forward == (0.2, 0.0)


@pytest.mark.parametrize(
    ("bad", "kind"),
    [
        ("NaN", "non_finite"),
        ("1e999", "non_finite"),
        ('"3"', "bad_type"),
        ("true", "bad_type"),
        ("9e7", "bad_type"),
    ],
)
def test_bad_offset_is_a_rejected_envelope(bad, kind):
    t, _ = make()
    text = '{"header":{"stamp":1,"offset_ms":' + bad + '},"twist":{"linear":{"x":0},"angular":{"z":0}}}'
    assert t.on_stamped(text, T0_NS) is None
    assert t.rejected == 1 and t.total_seen == 0
    assert (t.last_error or "").startswith(kind)


def test_tracker_refuses_a_negative_max_age():
    with pytest.raises(ValueError, match="max_command_age_ms"):
        LatencyTracker(max_command_age_ms=-1.0)
