import math
from dataclasses import replace

import pytest

from arbiter_core.controllers import (
    ALGORITHMS,
    MISSIONS,
    GoToGoalController,
    PurePursuitController,
    make_controller,
)
from arbiter_core.kinematics import (
    Limits,
    Pose,
    RobotState,
    clamp_twist,
    distance_error,
    heading_error,
    quaternion_to_yaw,
    step,
    wrap_angle,
    yaw_to_quaternion,
)
from arbiter_core.mission import Mission

DT = 0.02  # 50 Hz, the simulator's rate


def test_wrap_angle():
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert wrap_angle(-3 * math.pi / 2) == pytest.approx(math.pi / 2)
    assert wrap_angle(0.3) == pytest.approx(0.3)


def test_errors():
    pose = Pose(1.0, 1.0, math.pi)
    assert distance_error(pose, (4.0, 5.0)) == 5.0
    # bearing to (1, 2) is +pi/2, heading pi: error -pi/2
    assert heading_error(pose, (1.0, 2.0)) == pytest.approx(-math.pi / 2)
    # bearing 0 vs heading pi wraps to +-pi, never beyond
    assert abs(heading_error(pose, (2.0, 1.0))) == pytest.approx(math.pi)


def test_straight_line_respects_acceleration_limit():
    lim = Limits(max_linear=1.0, max_angular=2.0, max_linear_accel=1.0, max_angular_accel=4.0)
    s = RobotState()
    s = step(s, 1.0, 0.0, 0.5, lim)
    assert s.v == pytest.approx(0.5)  # 1 m/s^2 for 0.5 s
    for _ in range(100):
        s = step(s, 5.0, 0.0, DT, lim)
    assert s.v == 1.0  # clamped to max_linear
    assert s.pose.y == 0.0 and s.pose.x > 1.0


def test_arc_integration_is_exact():
    s = RobotState(v=1.0, w=1.0)
    lim = Limits(max_linear=1.0, max_angular=1.0)
    for _ in range(round(math.pi / 2 / DT)):
        s = step(s, 1.0, 1.0, DT, lim)
    # quarter circle of radius 1 from (0,0) heading +x ends near (1, 1) heading +y
    assert s.pose.x == pytest.approx(1.0, abs=0.02)
    assert s.pose.y == pytest.approx(1.0, abs=0.02)
    assert s.pose.theta == pytest.approx(math.pi / 2, abs=0.02)


def test_non_finite_commands_stop():
    assert clamp_twist(math.nan, math.inf) == (0.0, 0.0)
    assert clamp_twist(-9.0, 9.0, Limits(1.0, 2.0)) == (-1.0, 2.0)
    s = step(RobotState(v=0.5), math.nan, math.nan, DT)
    assert s.v < 0.5


def test_quaternion_round_trip():
    for yaw in (-3.0, -1.0, 0.0, 0.5, 3.1):
        assert quaternion_to_yaw(yaw_to_quaternion(yaw)) == pytest.approx(yaw)


def test_mission_progress_advances_within_tolerance():
    m = replace(Mission.route([(1.0, 0.0), (1.0, 1.0)]), tolerance=0.2)
    assert m.advanced(Pose(0.0, 0.0)) is m and m.goal == (1.0, 0.0)
    m1 = m.advanced(Pose(0.9, 0.0))
    assert m1.goal == (1.0, 1.0) and m1.index == 1 and m.index == 0  # a new value; the old one unchanged
    assert m1.advanced(Pose(1.0, 0.95)).done
    with pytest.raises(ValueError):
        Mission.named("nope", "go_to_goal")


def run_mission(algorithm: str, mission: str, limit_s: float = 120.0):
    ctrl = make_controller(algorithm)
    prog = Mission.named(mission, algorithm)
    state = RobotState()
    reached = []
    t = 0.0
    while not prog.done and t < limit_s:
        before = prog.index
        prog = prog.advanced(state.pose)
        if prog.index != before:
            reached.extend(range(before, prog.index))
        if prog.done:
            break
        v, w = ctrl.command(state.pose, prog)
        state = step(state, v, w, DT)
        t += DT
    return prog, reached, t, state


@pytest.mark.parametrize("algorithm", ["go_to_goal", "pure_pursuit"])
@pytest.mark.parametrize("mission", list(MISSIONS))
def test_autonomous_controllers_reach_every_waypoint(algorithm, mission):
    prog, reached, t, state = run_mission(algorithm, mission)
    assert prog.done, f"{algorithm} stalled at waypoint {prog.index} after {t:.1f}s"
    assert reached == list(range(len(MISSIONS[mission])))
    assert t < 60.0
    assert distance_error(state.pose, MISSIONS[mission][-1]) <= prog.tolerance


def test_manual_controller_returns_the_held_command():
    c = make_controller("manual")
    c.v, c.w = 0.3, -0.2
    assert c.command(Pose(), Mission.named("square", "manual")) == (0.3, -0.2)
    assert set(ALGORITHMS) == {
        "manual", "go_to_goal", "pure_pursuit", "stanley", "regulated_pure_pursuit", "kanayama",
    }  # fmt: skip
    with pytest.raises(ValueError):
        make_controller("teleport")


def test_controllers_stop_when_mission_done():
    prog = Mission.route([(0.0, 0.0)]).advanced(Pose())
    assert prog.done
    assert GoToGoalController().command(Pose(), prog) == (0.0, 0.0)
    assert PurePursuitController().command(Pose(), prog) == (0.0, 0.0)
