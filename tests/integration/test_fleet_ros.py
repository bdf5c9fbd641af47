"""A fleet console's stop reaches a real ROS 2 action server on DDS (issue 56, with the [ros] extra): the
robot runs ``arbiter-backend --transport ros`` on the site's router (test_fleet.py's access control), an
rclpy action server named as Nav2's navigator drives its ``/cmd_vel`` while its goal runs (a foreign
controller to the backend), and a console asks ``arbiter/robot1/stop`` with the fleet screen's client.

The console the router lets stop robot1 gets the robot's answer naming the cancelled goal; the action
server saw one cancel, the goal ends canceled within a second or two, and zeros go out on the robot's
command output and on ``/cmd_vel``. A console that may see robot1 but not stop it gets one line, and the
goal executes on."""

import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from arbiter_core import fleet
from arbiter_tui.fleet.client import FleetClient

from ..support.backend import BackendProc, start_backend
from ..support.ros import Navigator, Peer, Twist, use_test_domain
from ..support.waits import wait_for
from .test_fleet import LEASE_MS, acl_router, announced, console, row

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)

STATUS_CANCELED = 5  # action_msgs/msg/GoalStatus


@dataclass
class Site:
    mode: str  # "bridge" or "no-bridge"
    backend: BackendProc
    peer: Peer
    nav: Navigator
    client: object  # the rclpy ActionClient that sends the goals
    supervisor: FleetClient  # may stop robot1 (the router's access control)
    viewer: FleetClient  # sees robot1, may not stop it
    cmd: list  # (monotonic, linear.x, angular.z) of every Twist on /cmd_vel, whoever sent it
    measured: list  # the same on /cmd_vel_measured, the backend's command output


def twist_at(m):
    return time.monotonic(), m.linear.x, m.angular.z


@pytest.fixture(scope="module", params=["bridge", "no-bridge"])
def site(request, ros_domain, tmp_path_factory):
    """The router, robot1's backend (with its rosbridge endpoint, or ``--no-bridge`` as beside the stock
    rosbridge_server), the navigator's peer and two consoles."""
    from rclpy.action import ActionClient

    tmp: Path = tmp_path_factory.mktemp("fleet-ros")
    router, endpoint = acl_router(tmp)
    started: list = []
    try:
        backend = start_backend(
            "--transport", "ros", *(["--no-bridge"] if request.param == "no-bridge" else []),
            "--zenoh", endpoint, "--robot-name", "robot1", "--zenoh-lease", str(LEASE_MS),
            "--zenoh-config", str(tmp / "robot1.json5"), timeout=30,
        )  # fmt: skip
        started.append(backend.stop)
        peer = Peer("fake_nav2", threads=4)
        started.append(peer.close)
        nav = Navigator(peer, "/cmd_vel")
        client = ActionClient(peer.node, nav.action_type, "/navigate_to_pose")
        cmd = peer.collect(Twist, "/cmd_vel", twist_at)
        measured = peer.collect(Twist, "/cmd_vel_measured", twist_at)
        supervisor = console(endpoint, tmp / "supervisor.json5")
        started.append(supervisor.close)
        viewer = console(endpoint, tmp / "console-all.json5")
        started.append(viewer.close)
        assert client.wait_for_server(timeout_sec=15)
        assert wait_for(lambda: peer.matched("/cmd_vel_measured") > 0, timeout=15)
        assert wait_for(lambda: announced(supervisor, "robot1") and announced(viewer, "robot1"), timeout=15)
        yield Site(request.param, backend, peer, nav, client, supervisor, viewer, cmd, measured)
        client.destroy()
        nav.destroy()
    finally:
        for close in reversed(started):
            close()
        router.close()


@pytest.fixture
def goal(site):
    """A goal accepted and executing, its commands on /cmd_vel seen by the backend as a foreign driver;
    cancelled at the end if it still runs."""
    sent = site.client.send_goal_async(site.nav.action_type.Goal(order=1))
    assert wait_for(sent.done, timeout=10)
    handle = sent.result()
    assert handle.accepted
    result = handle.get_result_async()
    assert wait_for(lambda: site.nav.executing == 1, timeout=5)
    assert wait_for(lambda: row(site.supervisor, "robot1").driver == "foreign", timeout=10), row(
        site.supervisor, "robot1"
    )
    yield handle, result
    if not result.done():
        handle.cancel_goal_async()
        assert wait_for(result.done, timeout=5)


@pytest.mark.parametrize("site", ["bridge"], indirect=True)  # the router refuses: the backend never knows
def test_a_console_that_may_not_stop_the_robot_gets_one_line_and_the_goal_executes_on(site, goal):
    _handle, result = goal
    cancels = len(site.nav.cancels)
    t0 = time.monotonic()
    refused = site.viewer.stop("robot1")
    assert refused == (
        "not stopped: this console may not stop robot1 (the router let the stop through to nobody: "
        "its access control on arbiter/robot1/stop)"
    )
    assert time.monotonic() - t0 < 0.8 * fleet.STOP_TIMEOUT_S
    time.sleep(1.5)  # what a stop would have done by now (a cancel is waited 1 s at most): nothing
    assert len(site.nav.cancels) == cancels and site.nav.executing == 1 and not result.done()
    after = [v for t, v, _w in site.cmd if t > t0 + 0.5]
    assert after and all(v == pytest.approx(0.3) for v in after), after[-5:]  # driving on, no zeros


def test_a_stop_from_the_fleet_cancels_the_ros_action_servers_goal_and_zeros_follow(site, goal):
    _handle, result = goal
    cancels = len(site.nav.cancels)
    t0 = time.monotonic()
    answer = site.supervisor.stop("robot1")
    took = time.monotonic() - t0
    assert isinstance(answer, fleet.StopAnswer), answer
    words = answer.words()
    assert words == "stopped: 1 goal of /navigate_to_pose cancelled, zero sent", words
    assert answer.driver == "foreign" and answer.zero and answer.sure and answer.still is None
    assert took < fleet.STOP_ANSWER_S + 1.0, took

    # the action server saw the cancel, and its goal ended canceled
    assert wait_for(lambda: result.done(), timeout=2), site.nav.ended
    ended = time.monotonic()
    assert len(site.nav.cancels) == cancels + 1 and site.nav.cancels[-1] > t0
    assert result.result().status == STATUS_CANCELED
    assert site.nav.ended[-1] == "canceled" and site.nav.executing == 0

    # a zero on the robot's command output, then zeros on /cmd_vel while nothing else drives there
    assert wait_for(lambda: any(t > t0 and v == w == 0.0 for t, v, w in site.measured), timeout=2)
    assert wait_for(lambda: any(t > ended and v == w == 0.0 for t, v, w in site.cmd), timeout=2)
    time.sleep(0.5)  # the backend's zeros go on for a second: none of the goal's commands among them
    late = [(v, w) for t, v, w in site.cmd if t > ended + 0.3]
    assert late and all(v == w == 0.0 for v, w in late), late[-5:]
    print(f"fleet stop over --transport ros ({site.mode}) answered in {took * 1e3:.0f} ms: {words}")
