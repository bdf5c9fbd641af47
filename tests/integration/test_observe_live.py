"""Observe mode, live (issue 35, item 1): a controller the console does not run — here a roslibpy script
with its own pure pursuit, standing in for Nav2 or a student's node — publishes its plan and drives the
simulator through its command topic; the console, sending nothing, records its run from the robot's
topics through the real rosbridge protocol, and grades it as a driven run."""

import math
import threading
import time

import numpy as np
import roslibpy

from arbiter_core.controllers import make_controller
from arbiter_core.kinematics import Pose, quaternion_to_yaw
from arbiter_core.mission import Mission
from arbiter_tui.analytics import tracking as T
from arbiter_tui.analytics.runs import COMPLETED
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.robot import RobotSession
from arbiter_tui.session.settings import Settings

from ..support.backend import get_json, start_backend
from ..support.waits import wait_for

GOAL = (1.2, 0.6)


def foreign_controller(port: int, done: threading.Event, plan: list) -> None:
    """Pure pursuit on the robot's side of the link: odometry in, Twist out at 20 Hz, the plan (the
    straight line to GOAL, 13 points) republished every half second, as Nav2 replans."""
    ros = roslibpy.Ros("127.0.0.1", port)
    ros.run(timeout=10)
    pose: list[Pose] = []
    odom = roslibpy.Topic(ros, "/odom", "nav_msgs/Odometry")
    odom.subscribe(
        lambda m: pose.append(
            Pose(m["pose"]["pose"]["position"]["x"], m["pose"]["pose"]["position"]["y"],
                 quaternion_to_yaw(m["pose"]["pose"]["orientation"]))
        )
    )  # fmt: skip
    cmd = roslibpy.Topic(ros, "/cmd_vel_measured", "geometry_msgs/Twist")
    path = roslibpy.Topic(ros, "/plan", "nav_msgs/Path")
    cmd.advertise()
    path.advertise()
    controller = make_controller("pure_pursuit")
    try:
        assert wait_for(lambda: bool(pose), 10)
        start = (pose[-1].x, pose[-1].y)
        plan[:] = [
            (start[0] + (GOAL[0] - start[0]) * k / 12, start[1] + (GOAL[1] - start[1]) * k / 12)
            for k in range(13)
        ]
        mission = Mission.route([GOAL], start=start)
        poses = [
            {"pose": {"position": {"x": x, "y": y, "z": 0.0}, "orientation": {"w": 1.0}}} for x, y in plan
        ]
        msg = {"header": {"frame_id": "odom"}, "poses": poses}
        deadline = time.monotonic() + 20
        n = 0
        while time.monotonic() < deadline and not done.is_set():
            if n % 10 == 0:
                path.publish(roslibpy.Message(msg))
            mission = mission.advanced(pose[-1])
            v, w = (0.0, 0.0) if mission.done else controller.command(pose[-1], mission)
            cmd.publish(
                roslibpy.Message(
                    {"linear": {"x": v, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": w}}
                )
            )
            n += 1
            time.sleep(0.05)
    finally:
        ros.close()


def test_the_console_records_a_foreign_controllers_run_from_the_robots_topics():
    backend = start_backend()
    settings = Settings(
        handle_signals=False, observe=True, observe_label="student_pp", cmd_topic="/cmd_vel_measured"
    )
    link = RosLink("127.0.0.1", backend.bridge_port)
    session = RobotSession(settings, link)
    done, plan = threading.Event(), []
    driver = threading.Thread(target=foreign_controller, args=(backend.bridge_port, done, plan), daemon=True)
    try:
        assert wait_for(lambda: link.state == CONNECTED, 15)
        assert wait_for(lambda: link.telemetry.odom_count > 0, 10)
        # the robot stands, no run (issue 54, item 3): one sample where it stands, not one each 0.1 s
        seen = link.telemetry.odom_count
        assert wait_for(lambda: link.telemetry.odom_count >= seen + 50, 10)  # a second of odometry
        assert len(session.store) == 1 and session.store.points()[0].runId is None, len(session.store)
        driver.start()

        def completed():
            return [r for r in session.store.runs() if r.outcome == COMPLETED]

        assert wait_for(lambda: completed(), 25), session.store.runs()
        done.set()
        (run,) = completed()
        assert run.algorithm == "student_pp" and run.mission == f"goal (+{GOAL[0]:.2f}, +{GOAL[1]:.2f})"
        samples = [p for p in session.store.points() if p.runId == run.id]
        assert len(samples) > 10 and all(p.algorithm == "student_pp" for p in samples)
        assert any(abs(p.linearVel) > 0.1 for p in samples)  # the commands it sent, as the samples' v
        assert all(p.latencyMs is None for p in samples)  # a plain Twist carries no stamp
        # the cross-track figures: the simulator's pose (its odometry, exact here) against the plan
        xy = np.array([(p.x, p.y) for p in samples])
        xte = T.cross_track(xy[:, 0], xy[:, 1], np.array(plan))
        assert math.isclose(run.tracking.xte_mean_m, float(xte.mean()), abs_tol=0.01)
        assert run.tracking.path_ratio is not None and 0.8 < run.tracking.path_ratio < 1.3
        assert get_json(f"{backend.api}/api/latency")["stats"]["count"] == 0  # the console sent nothing
    finally:
        done.set()
        driver.join(5)
        link.close()
        backend.stop()
