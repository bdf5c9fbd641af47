"""One marker and colour per controller on every plot, none a waypoint's, goal's or the robot's."""

import pytest

from arbiter_core.controllers import ALGORITHMS
from arbiter_tui.analytics.styles import GOAL, ROBOT_ARROWS, WAYPOINT, style_of


def test_every_controller_has_its_own_marker_and_colour_apart_from_the_mission_and_robot():
    styles = [style_of(name) for name in ALGORITHMS]
    assert len({s.marker for s in styles}) == len(ALGORITHMS)
    assert len({s.colour for s in styles}) == len(ALGORITHMS)
    assert len({s.mpl_marker for s in styles}) == len(ALGORITHMS)
    assert len({s.mpl_colour for s in styles}) == len(ALGORITHMS)
    reserved = {WAYPOINT.marker, GOAL.marker, *ROBOT_ARROWS}
    assert not {s.marker for s in styles} & reserved
    assert not {s.colour for s in styles} & {WAYPOINT.colour, GOAL.colour}


@pytest.mark.parametrize("name", ["nav2_mppi", "student_node", "dwb"])
def test_an_unknown_controller_gets_a_style_from_its_name_not_its_position(name):
    assert style_of(name) == style_of(name)
    assert style_of(name) not in {style_of(a) for a in ALGORITHMS}
    assert style_of(name).marker not in {WAYPOINT.marker, GOAL.marker, *ROBOT_ARROWS}


def test_the_terminal_plots_draw_each_controller_with_its_style():
    from arbiter_tui.shell.widgets.plots import algorithm_style

    for name in ALGORITHMS:
        assert algorithm_style(name) == (style_of(name).marker, style_of(name).colour)
