"""Observe mode on DDS (issue 35, item 1, with the [ros] extra): an rclpy node — a controller the console
does not run — follows odometry, publishes its nav_msgs/Path and a TwistStamped command; the console,
on the backend's `--transport ros` endpoint and sending nothing, records its run from those topics."""

import math
import threading
import time

import numpy as np
import pytest

from arbiter_core.controllers import make_controller
from arbiter_core.kinematics import Pose, quaternion_to_yaw
from arbiter_core.mission import Mission
from arbiter_tui.analytics import tracking as T
from arbiter_tui.analytics.runs import COMPLETED
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.robot import RobotSession
from arbiter_tui.session.settings import Settings

from ..support.backend import start_backend
from ..support.ros import Odometry, Peer, PoseStamped, TwistStamped, use_test_domain
from ..support.waits import wait_for

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)
GOAL = (1.0, -0.5)


def drive_with_rclpy(peer: Peer, done: threading.Event, plan: list) -> None:
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Path

    node = peer.node
    poses: list[Pose] = []
    node.create_subscription(
        Odometry, "/odom",
        lambda m: poses.append(Pose(m.pose.pose.position.x, m.pose.pose.position.y, quaternion_to_yaw(
            {"x": m.pose.pose.orientation.x, "y": m.pose.pose.orientation.y,
             "z": m.pose.pose.orientation.z, "w": m.pose.pose.orientation.w}))),
        10,
    )  # fmt: skip
    drive = node.create_publisher(Twist, "/cmd_vel_measured", 10)  # what the simulator takes
    said = node.create_publisher(TwistStamped, "/robot_cmd", 10)  # what the robot's controller says it sent
    path_pub = node.create_publisher(Path, "/plan", 10)
    assert wait_for(lambda: bool(poses), 15)
    start = (poses[-1].x, poses[-1].y)
    plan[:] = [
        (start[0] + (GOAL[0] - start[0]) * k / 10, start[1] + (GOAL[1] - start[1]) * k / 10)
        for k in range(11)
    ]
    path = Path()
    path.header.frame_id = "odom"
    for x, y in plan:
        p = PoseStamped()
        p.pose.position.x, p.pose.position.y, p.pose.orientation.w = x, y, 1.0
        path.poses.append(p)
    mission, controller = Mission.route([GOAL], start=start), make_controller("pure_pursuit")
    deadline, n = time.monotonic() + 25, 0
    while time.monotonic() < deadline and not done.is_set():
        if n % 10 == 0:
            path_pub.publish(path)
        mission = mission.advanced(poses[-1])
        v, w = (0.0, 0.0) if mission.done else controller.command(poses[-1], mission)
        cmd = Twist()
        cmd.linear.x, cmd.angular.z = v, w
        drive.publish(cmd)
        stamped = TwistStamped()
        stamped.header.stamp = node.get_clock().now().to_msg()
        stamped.twist = cmd
        said.publish(stamped)
        n += 1
        time.sleep(0.05)


def test_the_console_records_an_rclpy_controllers_run_on_dds():
    backend = start_backend("--transport", "ros", timeout=30)
    peer = Peer("arbiter_foreign_controller")
    settings = Settings(
        handle_signals=False, observe=True, observe_label="rclpy_pp", cmd_topic="/robot_cmd", cmd_stamped=True
    )
    link = RosLink("127.0.0.1", backend.bridge_port)
    session = RobotSession(settings, link)
    done, plan = threading.Event(), []
    driver = threading.Thread(target=drive_with_rclpy, args=(peer, done, plan), daemon=True)
    try:
        assert wait_for(lambda: link.state == CONNECTED, 20)
        assert wait_for(lambda: link.telemetry.odom_count > 0, 15)
        driver.start()

        def completed():
            return [r for r in session.store.runs() if r.outcome == COMPLETED]

        assert wait_for(lambda: completed(), 30), session.store.runs()
        done.set()
        (run,) = completed()
        assert run.algorithm == "rclpy_pp" and run.mission == f"goal (+{GOAL[0]:.2f}, {GOAL[1]:+.2f})"
        samples = [p for p in session.store.points() if p.runId == run.id]
        assert len(samples) > 5
        # a TwistStamped's age on arrival: DDS, the bridge and the WebSocket, one host's clock
        ages = [p.latencyMs for p in samples if p.latencyMs is not None]
        assert ages and all(0.0 <= a < 1000.0 for a in ages), ages
        xy = np.array([(p.x, p.y) for p in samples])
        xte = T.cross_track(xy[:, 0], xy[:, 1], np.array(plan))
        assert math.isclose(run.tracking.xte_mean_m, float(xte.mean()), abs_tol=0.01)
    finally:
        done.set()
        driver.join(5)
        link.close()
        peer.close()
        backend.stop()
