"""A stop reaches a real ROS 2 action server on DDS (issue 46, item 1, with the [ros] extra): an rclpy
action server named as Nav2's navigator drives the robot while its goal is active; the console, observing
through `arbiter-backend --transport ros`, cancels every goal with ``action_msgs/srv/CancelGoal`` on
``/navigate_to_pose/_action/cancel_goal`` through rosbridge's ``call_service``, and the robot stands."""

import threading
import time

import pytest

from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.robot import RobotSession
from arbiter_tui.session.settings import CONNECT, Settings

from ..support.backend import start_backend
from ..support.ros import Navigator, Peer, use_test_domain
from ..support.waits import wait_for

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)


def test_a_stop_cancels_a_ros_action_servers_goal_through_rosbridge(tmp_path):
    from rclpy.action import ActionClient

    backend = start_backend("--transport", "ros")
    peer = Peer("fake_nav2", threads=4)
    settings = Settings(mode=CONNECT, handle_signals=False, export_dir=tmp_path, observe=True,
                        cmd_topic="/cmd_vel_measured")  # fmt: skip
    link = RosLink("127.0.0.1", backend.bridge_port)
    session = RobotSession(settings, link)
    try:
        nav = Navigator(peer, "/cmd_vel_measured")
        action = nav.action_type
        client = ActionClient(peer.node, action, "/navigate_to_pose")
        assert client.wait_for_server(timeout_sec=15)
        assert wait_for(lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 20)
        accepted = threading.Event()
        client.send_goal_async(action.Goal(order=1)).add_done_callback(lambda f: accepted.set())
        assert accepted.wait(10)
        assert wait_for(lambda: link.telemetry.v > 0.1, 10), "the navigator drives the robot"
        session.stop_all("stop key")
        t0 = time.monotonic()
        assert wait_for(lambda: max(abs(link.telemetry.v), abs(link.telemetry.w)) < 0.01, 10)
        took = time.monotonic() - t0
        assert session.remote_stop.wait_idle(10)
        report = session.remote_stop.reports[-1]
        assert "cancelled 1 goal of /navigate_to_pose" in report.text(), report.text()
        assert not report.unsure and took <= 1.0, (took, report.cancels)
        # the other Nav2 servers are not there: said as such, not as failures
        assert "could not cancel" not in report.text()
        nav.destroy()
        client.destroy()
    finally:
        session.close()
        link.close()
        peer.close()
        backend.stop()
