"""The mission's lifecycle as one immutable value (control/mission.py), and the one engine that drives it:
the live console's RobotSession, which `compare` now drives too."""

import dataclasses

import pytest

from arbiter_core.controllers import MissionProgress
from arbiter_tui.control import mission as M
from arbiter_tui.session import compare


def test_the_state_is_immutable_and_each_step_returns_a_new_one():
    s0 = M.MissionState()
    with pytest.raises(dataclasses.FrozenInstanceError):
        s0.running = True  # type: ignore[misc]
    s1 = M.selecting_algorithm(s0, "stanley")
    s2 = M.starting(s1, MissionProgress.named("square"), "square", now_ms=1000.0)
    assert (s0.algorithm, s0.running) == ("manual", False)
    assert (s1.algorithm, s1.running) == ("stanley", False)
    assert s2.running and s2.started_ms == 1000.0 and s2.finished is None


def test_a_run_stopped_halfway_is_what_g_resumes_with_its_controller_and_label():
    progress = MissionProgress.named("square")
    progress.index = 2
    running = M.starting(M.selecting_algorithm(M.MissionState(), "pure_pursuit"), progress, "square", 0.0)
    stopped = M.stopping(running)
    assert not stopped.running
    assert stopped.interrupted == M.Resumable(progress, "pure_pursuit", "square")
    # resumed and stopped again: the label is not "square, resumed, resumed"
    again = M.stopping(M.starting(stopped, progress, "square" + M.RESUMED, 0.0))
    assert again.interrupted is not None and again.interrupted.label == "square"
    assert M.stopping(stopped) is stopped  # nothing runs: nothing changes


def test_a_completed_run_says_how_long_it_took_until_a_key_is_pressed():
    progress = MissionProgress.named("square")
    running = M.starting(M.MissionState(algorithm="go_to_goal"), progress, "square", now_ms=500.0)
    progress.index = len(progress.waypoints)
    done = M.completing(running, now_ms=21_200.0)
    assert not done.running and done.finished == "done: 4/4 in 20.7 s"
    assert M.acknowledged(done).finished is None
    assert M.stopping(done).interrupted is None  # a finished run leaves nothing to resume


def test_a_compare_run_ends_as_the_consoles_runs_do():
    """`compare` runs through RobotSession (the console's engine): a completed run is summarised with the
    console's outcome, and a mission it does not know is refused in words."""
    result = compare.run_one("go_to_goal", "square")
    assert result.completed and result.summary is not None and result.summary.outcome == "completed"
    with pytest.raises(ValueError, match="unknown mission"):
        compare.run_one("go_to_goal", "no_such_mission")
