"""The part of a stop beyond the console's own commands (session/remote_stop.py), on its own thread: the
cancels go out together, zero velocity follows for a second after their answers, one report per press.
The link is a double at the boundary the stop reaches through (the real one: test_stop_everywhere.py)."""

import threading

from arbiter_tui.control.stop import CANCEL_ALL, NAV2_ACTIONS, stop_scope
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.session.remote_stop import RemoteStop


class Reaching:
    """A link double at the boundary the stop reaches through: it answers cancels as told, counts zeros."""

    state = CONNECTED

    def __init__(self, answers: dict[str, tuple[bool, object]]):
        self.answers = answers
        self.zeros: list[str] = []
        self.calls: list[tuple[str, dict]] = []

    def call_service(self, service, args, timeout_s, done):
        self.calls.append((service, args))
        ok, values = self.answers.get(service, (False, f"Service {service} does not exist"))
        threading.Thread(target=done, args=(ok, values)).start()  # on another thread, as roslibpy's
        return True

    def publish_zero(self, topic, stamped):
        self.zeros.append(topic)
        return True


def test_a_remote_stop_cancels_zeros_and_reports_once_per_press():
    link = Reaching({"/navigate_to_pose/_action/cancel_goal": (True, {"goals_canceling": [{}]})})
    reports = []
    scope = stop_scope(False, True, cmd_topic="/cmd_vel")
    stop = RemoteStop(scope, lambda: link, lambda: None, reports.append)
    stop.request()
    stop.request()  # the same press seen twice (the input thread, then the UI): one stop
    assert stop.wait_idle(10)
    assert [c for c, _ in link.calls] == [f"/{a}/_action/cancel_goal" for a in NAV2_ACTIONS]
    assert all(args == CANCEL_ALL for _, args in link.calls)
    assert len(reports) == 1 and "cancelled 1 goal of /navigate_to_pose" in reports[0].text()
    assert 5 <= len(link.zeros) <= 15 and set(link.zeros) == {"/cmd_vel"}  # about 1 s at 10 Hz
    stop.close()
