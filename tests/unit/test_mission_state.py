"""The mission as one immutable value (arbiter_core/mission.py), shared by the console's control loop
(control/mission.py holds the selection around it) and the robot-side controller (arbiter_backend/
autonomy.py), and the one engine that drives it: the live console's RobotSession, which `compare` drives
too."""

import dataclasses

import pytest

from arbiter_backend.autonomy import Autonomy, Request
from arbiter_core.kinematics import Pose
from arbiter_core.mission import Mission, Phase
from arbiter_tui.control import mission as M
from arbiter_tui.session import compare


def test_a_mission_is_immutable_and_each_step_returns_a_new_one():
    m0 = Mission.named("square", "stanley", Pose(1.0, 2.0), now_ms=1000.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        m0.index = 3  # type: ignore[misc]
    assert m0.waypoints[0] == (3.0, 2.0) and m0.start == (1.0, 2.0)  # relative to where it starts
    m1 = m0.advanced(Pose(3.0, 2.05))
    assert (m0.index, m1.index) == (0, 1) and m1.goal == (3.0, 4.0) and m1.previous == (3.0, 2.0)
    assert m1.advanced(Pose(0.0, 0.0)) is m1  # nothing reached: the same value
    done = m1.ended(Phase.COMPLETED, now_ms=21_700.0)
    assert done.phase is Phase.COMPLETED and not done.running and done.summary() == "done: 4/4 in 20.7 s"
    assert done.ended(Phase.ABORTED, 30_000.0) is done  # an ended run ends once
    with pytest.raises(ValueError):
        Mission.route([])
    with pytest.raises(ValueError):
        Mission.to_goal(float("nan"), 0.0, "go_to_goal", Pose())


def test_a_run_stopped_halfway_is_what_g_resumes_with_its_controller_and_name():
    m = Mission.named("square", "pure_pursuit").advanced(Pose(2.0, 0.0)).advanced(Pose(2.0, 2.0))
    running = M.starting(M.selecting_algorithm(M.MissionState(), "pure_pursuit"), m)
    stopped = M.stopping(running, Phase.ABORTED, 5000.0)
    assert not stopped.running and stopped.interrupted is not None
    assert (stopped.interrupted.algorithm, stopped.interrupted.index, stopped.interrupted.label) == (
        "pure_pursuit", 2, "square")  # fmt: skip
    assert stopped.interrupted.summary() == "aborted at 2/4"
    # resumed and stopped again: the label is "square, resumed", never "square, resumed, resumed"
    resumed = stopped.interrupted.resumed_from(Pose(1.0, 1.0), "stanley", 6000.0, life=0)
    again = M.stopping(M.starting(stopped, resumed), Phase.OVERRIDDEN, 7000.0)
    assert resumed.label == "square, resumed" and again.interrupted is not None
    assert again.interrupted.label == "square, resumed" and again.interrupted.phase is Phase.OVERRIDDEN
    assert M.stopping(stopped, Phase.ABORTED, 8000.0) is stopped  # nothing runs: nothing changes


def test_a_completed_run_says_how_long_it_took_until_a_key_is_pressed():
    m = Mission.named("square", "go_to_goal", now_ms=500.0)
    running = M.starting(M.MissionState(algorithm="go_to_goal"), m)
    m_done = running.current.advanced(Pose(2, 0)).advanced(Pose(2, 2)).advanced(Pose(0, 2)).advanced(Pose())
    done = M.completing(dataclasses.replace(running, current=m_done), now_ms=21_200.0)
    assert not done.running and done.finished == "done: 4/4 in 20.7 s"
    assert M.acknowledged(done).finished is None
    assert M.stopping(done, Phase.ABORTED, 30_000.0).interrupted is None  # nothing left to resume


def test_after_a_goal_is_reached_n_shows_the_selected_mission_and_never_the_goals_count():
    """The defect: after a typed goal and n the panel said "Mission square done: 16/16 in 28.0 s" (the
    label of one run, the counts of another). Name, counts and time now come from one value."""
    goal = Mission.to_goal(1.0, 0.0, "go_to_goal", Pose(), now_ms=0.0)
    state = M.starting(M.MissionState(algorithm="go_to_goal"), goal)
    state = M.completing(dataclasses.replace(state, current=goal.advanced(Pose(1.0, 0.0))), now_ms=4000.0)
    assert state.finished == "done: 1/1 in 4.0 s" and state.current is not None
    assert state.current.label == "goal (+1.00, +0.00)"
    picked = M.selecting_mission(state, "figure_eight")
    assert picked.finished is None and picked.selected == "figure_eight"
    assert len(picked.preview().waypoints) == 16


def test_the_robot_side_controller_runs_the_same_mission_value():
    autonomy = Autonomy()
    assert autonomy.status()["state"] == "idle"
    autonomy.start(Request("go_to_goal", "corner"), Pose(1.0, 1.0), {"sec": 0, "nanosec": 0}, now_ms=100.0)
    assert isinstance(autonomy.mission, Mission) and autonomy.mission.phase is Phase.RUNNING
    assert autonomy.mission.waypoints == Mission.named("corner", "go_to_goal", Pose(1.0, 1.0)).waypoints
    assert autonomy.stop(now_ms=900.0) == (0.0, 0.0) and autonomy.stop(now_ms=950.0) is None
    assert autonomy.status()["state"] == Phase.ABORTED.value and autonomy.mission.ended_ms == 900.0


def test_a_compare_run_ends_as_the_consoles_runs_do():
    """`compare` runs through RobotSession (the console's engine): a completed run is summarised with the
    console's outcome, and a mission it does not know is refused in words."""
    result = compare.run_one("go_to_goal", "square")
    assert result.completed and result.summary is not None and result.summary.outcome == "completed"
    with pytest.raises(ValueError, match="unknown mission"):
        compare.run_one("go_to_goal", "no_such_mission")
