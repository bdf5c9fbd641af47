import pytest

from arbiter_tui.control.teleop import MOVE_KEYS, Teleop


def test_key_map_is_teleop_twist_keyboards():
    assert MOVE_KEYS["u"] == (1, 0, 1) and MOVE_KEYS["."] == (-1, 0, 1) and MOVE_KEYS["m"] == (-1, 0, -1)
    t = Teleop(speed=0.5, turn=1.0)
    for key, (x, _y, th) in MOVE_KEYS.items():
        t.press(key, 0.0)
        assert t.tick(0.1) == (x * 0.5, th * 1.0), key


def test_hold_to_move_then_exactly_one_zero():
    t = Teleop(key_timeout=0.6)
    assert t.tick(0.0) is None  # idle: nothing to send
    t.press("i", 0.0)
    assert t.tick(0.1) == (0.5, 0.0)
    t.press("i", 0.5)  # auto-repeat refreshes the deadline
    assert t.tick(1.0) == (0.5, 0.0)
    assert t.tick(1.2) == (0.0, 0.0)  # deadline 1.1 passed
    assert [t.tick(1.3 + i * 0.1) for i in range(5)] == [None] * 5


@pytest.mark.parametrize(
    ("key", "speed", "turn"),
    [
        ("q", 0.55, 1.1),
        ("z", 0.45, 0.9),
        ("w", 0.55, 1.0),
        ("x", 0.45, 1.0),
        ("e", 0.5, 1.1),
        ("c", 0.5, 0.9),
    ],
)
def test_scaling_keys(key, speed, turn):
    t = Teleop(speed=0.5, turn=1.0)
    assert t.press(key, 0.0) == "scale"
    assert (t.speed, t.turn) == pytest.approx((speed, turn))


def test_scaling_is_capped_by_limits_and_applies_while_moving():
    t = Teleop(speed=0.95, turn=1.9)
    t.press("u", 0.0)
    t.press("q", 0.1)
    assert t.tick(0.2) == (1.0, 2.0)  # DEFAULT_LIMITS 1.0 m/s, 2.0 rad/s


def test_stop_keys_and_modifiers():
    t = Teleop()
    t.press("i", 0.0)
    assert t.press("left_shift", 0.05) is None  # a bare Shift is not "anything else"
    assert t.tick(0.1) == (0.5, 0.0)
    assert t.press("space", 0.2) == "stop"
    assert t.tick(0.25) == (0.0, 0.0)
    assert t.tick(0.3) is None
    t.press("j", 1.0)
    assert t.press("k", 1.1) == "stop"
    assert t.tick(1.2) == (0.0, 0.0)
    assert t.press("1", 2.0) is None


def test_the_key_legend_is_drawn_from_the_key_map():
    from arbiter_tui.control.teleop import (
        GRID,
        SCALE_KEYS,
        STOP_KEYS,
        legend_compact,
        legend_long,
        scale_pairs,
    )

    in_grid = {k for row in GRID for k in row}
    assert in_grid - set(MOVE_KEYS) == {"k"} and "k" in STOP_KEYS
    assert {k for k in MOVE_KEYS if (len(k) == 1 and k.islower()) or k in ",."} == in_grid - {"k"}
    assert {k for up, down, _, _ in scale_pairs() for k in (up, down)} == set(SCALE_KEYS)
    for key in in_grid | set(SCALE_KEYS):
        assert key in legend_compact() and key in legend_long()
    assert "x1.1 / x0.9" in legend_long()


def test_every_stat_has_one_label_and_unit():
    from arbiter_tui.analytics.labels import STAT_LABELS, format_stat
    from arbiter_tui.analytics.store import STATS_FIELDS

    assert tuple(STAT_LABELS) == STATS_FIELDS
    assert format_stat("sampleCount", 12) == "12"
    assert format_stat("avgLinearVel", 0.12345) == "0.123 m/s"
    assert format_stat("totalPathLength", 3.14159) == "3.14 m"
    assert format_stat("avgHeadingError", 0.5, decimals=6) == "0.500000 rad"
    assert format_stat("p95Error", 0.5, unit=False) == "0.500"
