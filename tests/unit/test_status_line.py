"""The status line's parts fitted to the terminal's width: whole parts by priority, drops marked ``…``."""

import pytest

from arbiter_tui.link.base import CONNECTED, RECONNECTING
from arbiter_tui.session.views import Part, StatusView, cells, fit_parts

PAUSED = StatusView(
    link=CONNECTED, target="embedded 9090/8085", deploy="native", algorithm="manual", points=153
)


def test_everything_when_it_fits_or_no_width_is_given():
    full = "CONNECTED · embedded 9090/8085 · deploy native · manual · paused 153 — r to record"
    assert PAUSED.text() == full and PAUSED.text(len(full)) == full


def test_at_80_columns_the_deploy_mode_goes_first_and_the_count_and_algorithm_stay():
    # 78 columns: 80 less the status line's padding
    assert PAUSED.text(78) == "CONNECTED · embedded 9090/8085 · … · manual · paused 153 — r to record"
    recording = StatusView(link=CONNECTED, target="ws://127.0.0.1:9090", deploy="pi",
                           algorithm="regulated_pure_pursuit", collecting=True, points=1_000_000)  # fmt: skip
    shown = "CONNECTED · ws://127.0.0.1:9090 · … · regulated_pure_pursuit · ● REC 1000000"
    assert recording.text(78) == shown


def test_parts_give_way_in_order_of_priority_each_whole():
    seen = []
    for width in range(90, 9, -1):
        text = PAUSED.text(width)
        assert cells(text) <= width
        if not seen or seen[-1] != text:
            seen.append(text)
    assert seen == [
        "CONNECTED · embedded 9090/8085 · deploy native · manual · paused 153 — r to record",
        "CONNECTED · embedded 9090/8085 · … · manual · paused 153 — r to record",
        "CONNECTED · embedded 9090/8085 · … · manual · paused 153",  # the hint
        "CONNECTED · … · manual · paused 153",  # where the backend is
        "CONNECTED · … · paused 153",  # the algorithm
        "CONNECTED · …",  # the count: only the link is never left out
        "CONNECTED …",
        "CONNECTED…",
    ]


def test_an_alarm_is_never_left_out_and_a_long_one_ends_at_a_whole_word():
    down = StatusView(
        link=RECONNECTING, target="wss://robot1.lan:9090", algorithm="stanley", points=12,
        error="TLS failure: the server's certificate is not trusted (pass the robot's CA with --ca-file)",
        warning="no odometry on /robot1/diff_drive_controller/odom", api="api UNREACHABLE",
    )  # fmt: skip
    text = down.text(78)
    assert text == "DISCONNECTED (reconnecting) · … · TLS failure: the server's certificate is …"
    roomy = down.text(300)
    assert "api UNREACHABLE" in roomy and "no odometry on" in roomy and "· stanley ·" in roomy
    assert down.text(210).endswith("/odom · … · paused 12 · api UNREACHABLE")  # before the API's state


def test_fit_parts_rules():
    a, b, c = Part.of("aaaa", 0), Part.of("bbbb", 2), Part.of("cccc", 2)
    assert fit_parts([a, b, c], 100) == "aaaa · bbbb · cccc"
    assert fit_parts([a, b, c], 15) == "aaaa · bbbb · …"  # a tie: the rightmost first
    assert fit_parts([a, b, c], 10) == "aaaa · …"  # two parts left out side by side: one mark
    assert fit_parts([a, Part.of("", 1), c], 100) == "aaaa · cccc"  # an empty part is no part
    short = Part((("bbbb — long", 5), ("bbbb", 1)))
    assert fit_parts([a, short], 100) == "aaaa · bbbb — long" and fit_parts([a, short], 11) == "aaaa · bbbb"
    assert fit_parts([Part.of("one two three", 0)], 10) == "one two …"
    assert fit_parts([Part.of("abcdefghijkl", 0)], 5) == "abcd…"
    assert cells("ロボット") == 8 and fit_parts([a, Part.of("ロボット", 3)], 10) == "aaaa · …"


@pytest.mark.parametrize("width", [0, 1, 2])
def test_tiny_widths_never_overflow(width):
    assert cells(PAUSED.text(width)) <= width


def test_a_panel_value_takes_its_first_form_that_fits_else_breaks_between_whole_fields():
    from arbiter_tui.session.views import fit_fields

    pose = [["x +12.34", "y -15.00", "θ -3.14 rad"], ["x +12.34", "y -15.00", "θ -3.14"]]
    assert fit_fields(pose, None) == ["x +12.34 y -15.00 θ -3.14 rad"]  # not laid out: the longest
    assert fit_fields(pose, 29) == ["x +12.34 y -15.00 θ -3.14 rad"]
    assert fit_fields(pose, 27) == ["x +12.34 y -15.00 θ -3.14"]  # narrow: no unit, never a lone "rad"
    assert fit_fields(pose, 20) == ["x +12.34 y -15.00", "θ -3.14"]  # the last form, between fields
    done = ["figure_eight", "done: 16/16 in 45.3 s"]
    assert fit_fields([done], 27) == done
    assert fit_fields([["a-very-long-single-field"]], 5) == ["a-very-long-single-field"]  # left to the widget
