import json
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from arbiter_core.envelope import MAX_ENVELOPE_BYTES, EnvelopeError, build, parse, stamp_ms_from_ns
from arbiter_core.record import build_record, latency_ms


def test_build_has_microsecond_float_stamp_and_seq():
    text = build(0.5, -0.25, seq=7, clock_ns=lambda: 1_712_345_678_901_234_567)
    doc = json.loads(text)
    assert doc == {
        "header": {"stamp": 1712345678901.234, "seq": 7},
        "twist": {"linear": {"x": 0.5}, "angular": {"z": -0.25}},
    }
    cmd = parse(text)
    assert (cmd.stamp_ms, cmd.linear_x, cmd.angular_z, cmd.seq) == (1712345678901.234, 0.5, -0.25, 7)


def test_stamp_keeps_microseconds():
    assert stamp_ms_from_ns(1_000_000_123_456_789) == 1_000_000_123.456


def test_seed_integer_ms_envelope_is_accepted():
    seed = '{"header": {"stamp": 1712345678901}, "twist": {"linear": {"x": 0.4}, "angular": {"z": 0.0}}}'
    cmd = parse(seed)
    assert cmd.stamp_ms == 1712345678901.0
    assert cmd.seq is None


def test_record_has_seed_fields_and_latency_rounded_to_4_places():
    cmd = parse(build(0.4, 0.1, seq=3, clock_ns=lambda: 1_000_000_000_000_000_000))
    recv = 1_000_000_000_000_000_000 + 123_456_789  # 123.456789 ms later
    rec = build_record(cmd, recv, "native")
    assert rec.to_dict() == {
        "latency_ms": 123.4568,
        "linear_x": 0.4,
        "angular_z": 0.1,
        "timestamp": recv / 1e9,
        "deploy_mode": "native",
        "seq": 3,
    }
    assert latency_ms(cmd, recv - 200_000_000) < 0  # clock skew: negative latency is kept, not clipped


@pytest.mark.parametrize(
    ("text", "kind"),
    [
        ("{not json", "invalid_json"),
        ("", "invalid_json"),
        ("[1, 2]", "not_object"),
        ('"just a string"', "not_object"),
        ('{"twist": {"linear": {"x": 1}, "angular": {"z": 0}}}', "missing_field"),
        ('{"header": {}, "twist": {"linear": {"x": 1}, "angular": {"z": 0}}}', "missing_field"),
        ('{"header": {"stamp": 1}, "twist": {"linear": {}, "angular": {"z": 0}}}', "missing_field"),
        ('{"header": {"stamp": 1}, "twist": {"linear": {"x": 1}}}', "missing_field"),
        ('{"header": 5, "twist": {"linear": {"x": 1}, "angular": {"z": 0}}}', "bad_type"),
        ('{"header": {"stamp": "now"}, "twist": {"linear": {"x": 1}, "angular": {"z": 0}}}', "bad_type"),
        ('{"header": {"stamp": true}, "twist": {"linear": {"x": 1}, "angular": {"z": 0}}}', "bad_type"),
        ('{"header": {"stamp": 1}, "twist": {"linear": {"x": false}, "angular": {"z": 0}}}', "bad_type"),
        ('{"header": {"stamp": 1}, "twist": {"linear": {"x": null}, "angular": {"z": 0}}}', "bad_type"),
        ('{"header": {"stamp": 1}, "twist": {"linear": {"x": [1]}, "angular": {"z": 0}}}', "bad_type"),
        (
            '{"header": {"stamp": 1, "seq": 1.5}, "twist": {"linear": {"x": 1}, "angular": {"z": 0}}}',
            "bad_type",
        ),
        ('{"header": {"stamp": NaN}, "twist": {"linear": {"x": 1}, "angular": {"z": 0}}}', "non_finite"),
        ('{"header": {"stamp": 1}, "twist": {"linear": {"x": Infinity}, "angular": {"z": 0}}}', "non_finite"),
        (
            '{"header": {"stamp": 1}, "twist": {"linear": {"x": 1}, "angular": {"z": -Infinity}}}',
            "non_finite",
        ),
        ('{"header": {"stamp": 1e999}, "twist": {"linear": {"x": 1}, "angular": {"z": 0}}}', "non_finite"),
        (
            '{"header": {"stamp": 1}, "twist": {"linear": {"x": 1' + "0" * 400 + '}, "angular": {"z": 0}}}',
            "non_finite",
        ),
    ],
)
def test_rejections_have_specific_kinds(text, kind):
    with pytest.raises(EnvelopeError) as err:
        parse(text)
    assert err.value.kind == kind
    assert str(err.value)


def test_oversize_text_is_rejected_before_parsing():
    big = '{"header": {"stamp": 1, "pad": "' + "x" * MAX_ENVELOPE_BYTES + '"}}'
    with pytest.raises(EnvelopeError) as err:
        parse(big)
    assert err.value.kind == "too_large"
    with pytest.raises(EnvelopeError) as err:
        parse(big.encode())
    assert err.value.kind == "too_large"


def test_deep_nesting_is_invalid_not_a_crash():
    with pytest.raises(EnvelopeError) as err:
        parse("[" * 50_000 + "]" * 50_000)
    assert err.value.kind in ("invalid_json", "too_large")
    with pytest.raises(EnvelopeError):
        parse("[" * 20_000 + "]" * 20_000)


def test_build_refuses_non_finite():
    with pytest.raises(EnvelopeError):
        build(math.nan, 0.0)
    with pytest.raises(EnvelopeError):
        build(0.0, math.inf)


@given(st.one_of(st.text(max_size=200), st.binary(max_size=200)))
def test_arbitrary_input_raises_only_envelope_error(data):
    try:
        parse(data)
    except EnvelopeError as exc:
        assert exc.kind in EnvelopeError.KINDS


@given(
    st.floats(-1e3, 1e3, allow_nan=False),
    st.floats(-1e3, 1e3, allow_nan=False),
    st.one_of(st.none(), st.integers(0, 2**40)),
    st.integers(0, 2**62),
)
def test_round_trip(v, w, seq, ns):
    cmd = parse(build(v, w, seq=seq, clock_ns=lambda: ns))
    assert (cmd.linear_x, cmd.angular_z, cmd.seq) == (v, w, seq)
    assert cmd.stamp_ms == stamp_ms_from_ns(ns)
