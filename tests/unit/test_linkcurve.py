"""Error against latency on the analytics screen: the curve from a compare sweep, the measured p95 on it."""

import re

import pytest

from arbiter_tui.analytics.linkcurve import (
    FAILED,
    READY,
    RUNNING,
    CurveError,
    LinkCurve,
    LinkSweepView,
    curve_of,
    interpolate,
    measured_p95,
)


def test_interpolation_between_and_beyond_the_swept_latencies():
    xs, ys = (0.0, 100.0, 300.0), (0.01, 0.03, 0.07)
    assert interpolate(xs, ys, 50.0) == pytest.approx(0.02)
    assert interpolate(xs, ys, 200.0) == pytest.approx(0.05)
    assert interpolate(xs, ys, -5.0) == 0.01 and interpolate(xs, ys, 900.0) == 0.07


def test_the_marker_line_names_each_controllers_extra_error_at_the_measured_p95():
    curve = LinkCurve(
        "square", (0.0, 100.0, 300.0), (("stanley", (0.01, 0.02, 0.05)), ("kanayama", (0.04, 0.034, 0.03)))
    )
    view = LinkSweepView(READY, "square", curve, p95_ms=50.0)
    assert (
        view.text()
        == "at your p95 of 50 ms on square: stanley +0.005 m, kanayama -0.003 m (avg e_xt vs 0 ms)"
    )
    assert "beyond the sweep" in LinkSweepView(READY, "square", curve, p95_ms=400.0).text()
    assert (
        LinkSweepView(READY, "square", curve, p95_ms=0.42)
        .text()
        .startswith("at your p95 of 0.4 ms on square")
    )
    assert "no latency measured" in LinkSweepView(READY, "square", curve, p95_ms=None).text()
    assert "sweeping latency" in LinkSweepView(RUNNING, "square").text()
    held = LinkSweepView(RUNNING, "square", paused=True).text()
    assert "paused while the robot drives" in held and "goes on once it stops" in held and len(held) <= 98
    assert "sweeping latency" in LinkSweepView(RUNNING, "square", paused=False).text()
    failed = LinkSweepView(FAILED, "square", error="boom").text()
    assert failed == "latency sweep failed: boom (tried again in 30 s)"


def test_p95_of_recorded_latencies_ignores_unknown_ones_and_clamps_negative_ones():
    assert measured_p95([]) is None and measured_p95([float("nan")]) is None
    assert measured_p95([-3.0, *[float(i) for i in range(1, 20)]]) == 19.0
    assert measured_p95([-3.0]) == 0.0


def test_a_malformed_compare_answer_is_a_curve_error():
    for body in ({}, {"sweep": [{"link": {}}]}, {"sweep": []}, {"sweep": "x"}):
        with pytest.raises(CurveError):
            curve_of(body, "square")


FIVE = LinkCurve(
    "square",
    (0.0, 100.0, 300.0),
    tuple(
        (name, (0.01 * k, 0.012 * k, 0.02 * k))
        for k, name in enumerate(
            ("go_to_goal", "pure_pursuit", "stanley", "regulated_pure_pursuit", "kanayama"), start=1
        )
    ),
)


@pytest.mark.parametrize("width", [76, 96, 156])
def test_the_marker_line_fits_two_rows_leaving_out_whole_controllers_with_an_ellipsis(width):
    import textwrap

    view = LinkSweepView(READY, "square", FIVE, p95_ms=130.0)
    text = view.text(width, rows=2)
    assert len(textwrap.wrap(text, width)) <= 2
    full = view.text()
    if len(textwrap.wrap(full, width)) <= 2:
        assert text == full
    else:
        assert "…" in text
        shown = [n for n, _ in FIVE.errors if f"{n} " in text]
        assert shown == [n for n, _ in FIVE.errors][: len(shown)] and shown, "whole controllers, in order"
        for name in shown:  # none is cut inside its figure
            assert re.search(rf"{name} [+-]\d\.\d{{3}} m", text)


def test_the_legend_and_the_line_show_the_measured_p95_the_same_way():
    from arbiter_tui.analytics.linkcurve import format_ms

    for p95, shown in ((0.31, "0.3"), (4.0, "4.0"), (130.4, "130")):
        assert format_ms(p95) == shown
        assert f"at your p95 of {shown} ms" in LinkSweepView(READY, "square", FIVE, p95_ms=p95).text()
