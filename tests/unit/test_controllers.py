"""The three newer controllers (Stanley, regulated pure pursuit, Kanayama): each on a straight line and at a
turn, within the caps; regulated pure pursuit slows for curvature and near the goal."""

import math

import pytest

from arbiter_core.controllers import (
    KanayamaController,
    PurePursuitController,
    RegulatedPurePursuitController,
    StanleyController,
)
from arbiter_core.kinematics import Limits, Pose, RobotState, step
from arbiter_core.mission import Mission

NEW = (StanleyController, RegulatedPurePursuitController, KanayamaController)
LIMITS = Limits(max_linear=0.5, max_angular=1.0)


def line(goal=(4.0, 0.0)) -> Mission:
    return Mission.route([goal])


def drive(controller, mission: Mission, pose: Pose, seconds: float) -> tuple[list[Pose], Mission]:
    """The controller alone on the unicycle model at 10 Hz (commands) / 50 Hz (integration)."""
    state, path = RobotState(pose=pose), [pose]
    v = w = 0.0
    for n in range(int(seconds * 50)):
        if n % 5 == 0:
            mission = mission.advanced(state.pose)
            v, w = controller.command(state.pose, mission)
            assert abs(v) <= LIMITS.max_linear + 1e-9 and abs(w) <= LIMITS.max_angular + 1e-9
        state = step(state, v, w, 0.02, LIMITS)
        path.append(state.pose)
    return path, mission


@pytest.mark.parametrize("cls", NEW, ids=lambda c: c.__name__)
def test_on_a_straight_line_it_steers_back_onto_the_line_and_stays(cls):
    controller = cls(limits=LIMITS)
    v, w = controller.command(Pose(0.5, 0.3, 0.0), line())  # left of the line, parallel to it
    assert v > 0 and w < 0  # forward, turning right, towards the line
    v, w = controller.command(Pose(0.5, -0.3, 0.0), line())
    assert v > 0 and w > 0
    path, _ = drive(controller, line(), Pose(0.0, 0.3, 0.0), 8.0)
    late = [p for p in path if 2.0 <= p.x <= 3.5]
    assert late and max(abs(p.y) for p in late) < 0.05  # converged onto y = 0


@pytest.mark.parametrize("cls", NEW, ids=lambda c: c.__name__)
def test_at_a_turn_it_turns_towards_the_new_leg_and_follows_it(cls):
    controller = cls(limits=LIMITS)
    # the first leg is done: the robot stands at its end, facing along it
    mission = Mission.route([(2.0, 0.0), (2.0, 2.0)], index=1)
    _, w = controller.command(Pose(2.0, 0.0, 0.0), mission)
    assert w > 0  # the new leg goes left
    path, mission = drive(controller, mission, Pose(2.0, 0.0, 0.0), 12.0)
    assert mission.done
    on_leg = [p for p in path if 1.2 <= p.y <= 1.8]
    assert on_leg and max(abs(p.x - 2.0) for p in on_leg) < 0.15  # back on the leg x = 2 after the turn


@pytest.mark.parametrize("cls", NEW, ids=lambda c: c.__name__)
def test_the_caps_hold_whatever_the_pose(cls):
    tight = Limits(max_linear=0.2, max_angular=0.3)
    controller = cls(limits=tight)
    for x in (-1.0, 0.0, 1.0, 3.9):
        for y in (-1.0, -0.1, 0.0, 0.5):
            for th in (-3.0, -1.0, 0.0, 1.5, 3.1):
                v, w = controller.command(Pose(x, y, th), line())
                assert 0.0 <= v <= 0.2 + 1e-9 and abs(w) <= 0.3 + 1e-9 and math.isfinite(v + w)
    assert controller.command(Pose(0, 0, 0), Mission.route([(1.0, 0.0)], index=1)) == (0.0, 0.0)  # done


def test_regulated_pure_pursuit_slows_for_curvature_and_near_the_goal():
    plain, regulated = PurePursuitController(limits=LIMITS), RegulatedPurePursuitController(limits=LIMITS)
    curving = Pose(0.5, 0.4, 0.8)  # off the line, heading away: a tight arc back
    assert regulated.command(curving, line())[0] < plain.command(Pose(0.5, 0.0, 0.0), line())[0]
    far = regulated.command(Pose(1.0, 0.0, 0.0), line())[0]
    near = regulated.command(Pose(3.8, 0.0, 0.0), line())[0]
    assert far == pytest.approx(LIMITS.max_linear) and near < 0.5 * far
