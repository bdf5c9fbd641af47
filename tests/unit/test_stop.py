"""What a stop reaches in each mode (control/stop.py: one definition) and what it says it did; the stop
key that is never text, answered on the input thread even behind a dialog (shell/keys.py)."""

import pytest
from textual import events

from arbiter_tui.control.stop import (
    CANCEL_ALL,
    NAV2_ACTIONS,
    ActionCancel,
    Cancel,
    RobotSideStop,
    StopReport,
    cancel_failure,
    cancel_outcome,
    stop_scope,
)
from arbiter_tui.shell.keys import KeyRouter


def test_what_a_stop_reaches_in_each_mode():
    assert not stop_scope(simulated=True, observe=True).remote  # no network: nothing beyond the console
    plain = stop_scope(simulated=False, observe=False)
    assert plain.robot_side and plain.actions == () and plain.zero_topic is None
    watched = stop_scope(False, True, "/robot1", "cmd_vel", cmd_stamped=True)
    assert watched.actions == tuple(f"/robot1/{a}" for a in NAV2_ACTIONS)
    assert watched.zero_topic == "/robot1/cmd_vel" and watched.zero_stamped
    mine = stop_scope(False, True, "/robot1", "/cmd", actions=("/arm/move", "dock", "dock"))
    assert mine.actions == ("/arm/move", "/robot1/dock") and mine.zero_topic == "/cmd"
    assert stop_scope(False, False, actions=("dock",)).actions == ("/dock",)  # asked for: any mode
    assert CANCEL_ALL["goal_info"]["goal_id"]["uuid"] == [0] * 16  # every goal of the server


@pytest.mark.parametrize(
    ("values", "outcome", "goals"),
    [
        ({"return_code": 0, "goals_canceling": [{"goal_id": {}}, {"goal_id": {}}]}, Cancel.CANCELLED, 2),
        ({"return_code": 0, "goals_canceling": []}, Cancel.NO_GOAL, 0),
        ({"return_code": 2, "goals_canceling": []}, Cancel.NO_GOAL, 0),  # unknown goal: nothing runs
        ({"return_code": 1, "goals_canceling": []}, Cancel.FAILED, 0),  # refused
        ("not a response", Cancel.NO_GOAL, 0),
    ],
)
def test_a_cancel_answer_is_read_as_what_it_says(values, outcome, goals):
    got = cancel_outcome("/navigate_to_pose", values)
    assert (got.outcome, got.goals) == (outcome, goals)


def test_a_cancel_that_fails_tells_a_missing_server_from_another_failure():
    assert cancel_failure("/a", "Service /a/_action/cancel_goal does not exist").outcome is Cancel.NO_SERVER
    assert cancel_failure("/a", "Service /a/_action/cancel_goal is not available").outcome is Cancel.NO_SERVER
    assert cancel_failure("/a", "timed out").outcome is Cancel.FAILED


def test_the_report_says_what_was_stopped_and_what_could_not_be():
    none = tuple(ActionCancel(f"/{a}", Cancel.NO_SERVER) for a in NAV2_ACTIONS)
    lone = StopReport(cancels=none, zero_topic="/cmd_vel", zero_for_s=1.0)
    assert lone.unsure and lone.worth_saying()
    assert lone.text() == (
        "Stop: no action server on /navigate_to_pose, /navigate_through_poses and 6 more; sent zero "
        "velocity on /cmd_vel for 1 s only: a controller still publishing will override it"
    )
    nav2 = StopReport(cancels=(ActionCancel("/navigate_to_pose", Cancel.CANCELLED, 1), *none[1:]),
                      zero_topic="/cmd_vel", zero_for_s=1.0)  # fmt: skip
    assert not nav2.unsure
    assert nav2.text() == "Stop: cancelled 1 goal of /navigate_to_pose; zero velocity on /cmd_vel for 1 s"
    ours = StopReport(robot_side=RobotSideStop(stopped=True, run="stanley on corner at 1/2"))
    assert ours.text() == "Stop: stopped the robot-side stanley on corner at 1/2" and not ours.unsure
    # outside observe mode: a backend without --autonomy, or nothing running there, needs no words
    assert not StopReport(robot_side=RobotSideStop(error="403 autonomy off", enabled=False)).worth_saying()
    assert not StopReport(robot_side=RobotSideStop(stopped=False, run="idle")).worth_saying()
    unreachable = StopReport(robot_side=RobotSideStop(error="connection refused"))
    assert unreachable.unsure and "could not ask the robot-side controller: connection refused" in (
        unreachable.text())  # fmt: skip
    down = StopReport(link_down=True)
    assert down.unsure and "the link to the robot is down" in down.text()


def key(name: str, character: str | None = None) -> events.Key:
    return events.Key(name, character)


def test_ctrl_k_is_answered_on_the_input_thread_behind_a_dialog_and_again_in_its_place():
    stops, answered = [], []
    router = KeyRouter(lambda k, at: answered.append(k) or True, lambda: stops.append("stop"))
    router.set_direct(False)  # a dialog is in front: teleop keys go to the UI
    router.on_input_thread(key("g", "g"))  # queued for the UI (it may start a mission)
    event = key("ctrl+k", "\x0b")
    router.on_input_thread(event)
    assert stops == ["stop"] and answered == []  # at once, ahead of the queued g
    assert not router.taken(event)  # ...and the UI answers it again after the g
    router.on_input_thread(key("space", " "))
    assert stops == ["stop"]  # space behind a dialog: the UI's binding answers it (it may be text)


def test_a_key_carries_the_time_its_read_came_not_when_a_lock_let_it_through():
    """The parser makes a read's keys one by one as the input thread answers them: a key whose answer
    waited 20 ms on a lock must not make the next key of its read 20 ms later (a stall's burst spread
    out into a hand's pace); a later read gets its own time."""
    now, answered = [100.0], []

    def answer(name, at):  # the session's lock held elsewhere for 20 ms
        answered.append(at)
        now[0] += 0.02
        return True

    router = KeyRouter(answer, clock=lambda: now[0] + 5000.0, stamp=lambda: now[0])
    router.set_direct(True)
    for _ in range(3):  # one read: each key made right after the one before it was answered
        event = key("i", "i")
        event.time = now[0]
        router.on_input_thread(event)
    now[0] += 0.3  # the next read
    event = key("i", "i")
    event.time = now[0]
    router.on_input_thread(event)
    assert answered == [5100.0, 5100.0, 5100.0, pytest.approx(5100.36)]
