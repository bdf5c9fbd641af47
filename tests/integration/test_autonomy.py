"""The seed's autonomous behaviour node, on the robot (issue 35, item 2): ``arbiter-backend --autonomy``
runs one of the console's controllers (the same code, arbiter_core.controllers) on the robot's own
odometry, started through ``/api/autonomy``; the console, sending nothing, observes it through the real
rosbridge protocol and grades it as compare grades that controller on a perfect link."""

import json
import math
import urllib.error
import urllib.request

import pytest

from arbiter_tui.analytics.runs import COMPLETED
from arbiter_tui.cli import main
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.compare import run_one
from arbiter_tui.session.robot import RobotSession
from arbiter_tui.session.settings import Settings

from ..support.backend import get_json, start_backend
from ..support.waits import wait_for


def call(url: str, method: str, body: bytes | None = None) -> tuple[int, dict]:
    req = urllib.request.Request(url, data=body, method=method)
    try:
        with urllib.request.urlopen(req, timeout=5) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())


# corner, not square: the square ends where it starts, and an observed run is complete once the robot
# stands at its goal (analytics/observe.py)
@pytest.mark.parametrize("algorithm", ["stanley", "pure_pursuit"])
def test_the_robot_side_run_observed_by_the_console_is_what_compare_gives(algorithm):
    observe_robot_side(algorithm, start_backend("--autonomy"))


def observe_robot_side(algorithm: str, backend) -> None:
    """Start ``algorithm`` on ``corner`` through the backend's API, observe it from the console, and hold
    its figures against compare's on a perfect link (also the ROS-mode test's)."""
    settings = Settings(
        handle_signals=False, observe=True, observe_label=f"robot_{algorithm}", cmd_topic="/cmd_vel_measured"
    )
    link = RosLink("127.0.0.1", backend.bridge_port)
    session = RobotSession(settings, link)
    url = f"{backend.api}/api/autonomy"
    try:
        assert wait_for(lambda: link.state == CONNECTED, 15)
        assert wait_for(lambda: link.telemetry.odom_count > 0, 10)
        status, body = call(url, "POST", json.dumps({"algorithm": algorithm, "mission": "corner"}).encode())
        assert status == 200 and body["state"] == "running", body

        def completed():
            return [r for r in session.store.runs() if r.outcome == COMPLETED]

        assert wait_for(lambda: completed(), 60), (session.store.runs(), get_json(url))
        (run,) = completed()
        robot = get_json(url)
        assert robot["state"] == "completed" and robot["commands"] > 100, robot
        truth = run_one(algorithm, "corner")  # compare: the same controller, a perfect link
        assert truth.completed
        print(f"\nobserved {run.tracking.as_dict()} time {run.time_s:.2f}\n"
              f"compare  {truth.tracking.as_dict()} time {truth.time_s:.2f}")  # fmt: skip
        assert run.algorithm == f"robot_{algorithm}" and run.mission.startswith("goal (")
        # the figures the issue names: within 1 cm and 5 %
        assert math.isclose(run.tracking.xte_mean_m, truth.tracking.xte_mean_m, abs_tol=0.01)
        assert math.isclose(run.tracking.xte_max_m, truth.tracking.xte_max_m, abs_tol=0.01)
        assert math.isclose(run.stats.totalPathLength, truth.stats.totalPathLength, rel_tol=0.05)
        assert math.isclose(run.time_s, truth.time_s, rel_tol=0.05)
        assert get_json(f"{backend.api}/api/latency")["stats"]["count"] == robot["commands"] + 1  # + the stop
    finally:
        link.close()
        backend.stop()


def test_bad_requests_are_refused_in_one_line_and_nothing_moves():
    off = start_backend()
    on = start_backend("--autonomy", "--no-sim")  # no odometry: nothing to drive by
    try:
        status, body = call(f"{off.api}/api/autonomy", "POST", b'{"algorithm": "stanley"}')
        assert status == 403 and "--autonomy" in body["error"]
        url = f"{on.api}/api/autonomy"
        for raw, words in [
            (b'{"algorithm": "teleport"}', "algorithm must be one of"),
            (b'{"algorithm": "stanley", "mission": "moon"}', "mission must be one of"),
            (b'{"algorithm": "stanley", "speed": 0}', "speed must be in"),
            (b'{"algorithm": "stanley", "speed": 9}', "speed must be in"),
            (b'{"algorithm": "stanley", "turn": true}', "turn must be a finite number"),
            (b'{"algorithm": "stanley", "speed": NaN}', "not a number JSON allows"),
            (b'["stanley"]', "must be a JSON object"),
            (b"{", "not JSON"),
        ]:
            status, body = call(url, "POST", raw)
            assert status == 400 and words in body["error"], (raw, body)
        status, body = call(url, "POST", b'{"algorithm": "stanley", "pad": "' + b"x" * 5000 + b'"}')
        assert status == 413, body
        status, body = call(url, "POST", b'{"algorithm": "stanley"}')
        assert status == 409 and "no odometry" in body["error"], body
        assert call(url, "GET")[1]["state"] == "idle" and call(url, "DELETE")[1]["state"] == "idle"
        assert get_json(f"{on.api}/api/latency")["stats"]["count"] == 0  # nothing reached the robot
    finally:
        off.stop()
        on.stop()


def test_the_console_starts_stops_and_asks_from_the_command_line(capsys):
    backend = start_backend("--autonomy")
    try:
        tracker = ["--tracker", backend.api]
        assert wait_for(lambda: backend_has_odometry(backend), 10)
        assert main(["autonomy", "start", "kanayama", "--mission", "slalom", *tracker]) == 0
        assert "running · kanayama on slalom" in capsys.readouterr().out
        assert wait_for(lambda: get_json(f"{backend.api}/api/autonomy")["commands"] >= 5, 10)
        assert main(["autonomy", "stop", *tracker]) == 0
        assert "aborted · kanayama on slalom" in capsys.readouterr().out
        assert main(["autonomy", "start", "stanley", "--speed", "7", *tracker]) == 1
        assert "speed must be in" in capsys.readouterr().err
        assert main(["autonomy", "status", "--json", *tracker]) == 0
        assert json.loads(capsys.readouterr().out)["state"] == "aborted"
    finally:
        backend.stop()
    assert main(["autonomy", "status", "--tracker", backend.api, "--timeout", "1"]) == 3  # it is gone
    assert "/api/autonomy" in capsys.readouterr().err


def backend_has_odometry(backend) -> bool:
    topics = get_json(f"{backend.api}/api/topics")["topics"]
    return any(t["name"] == "/odom" and t["count"] > 0 for t in topics)
