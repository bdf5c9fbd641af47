"""Real robots' topic names: the embedded bus under a namespace, "no odometry" said plainly. (The
namespaced rclpy robot driven from the console is in test_ros.py, with the other ROS tests.)"""

import json

import aiohttp

from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell.app import make_app

from ..support.backend import get_json, start_backend
from ..support.tui import until


def settings(tmp_path):
    return Settings(handle_signals=False, export_dir=tmp_path, mode="connect")


def odometry(x: float) -> dict:
    return {
        "header": {"frame_id": "odom"},
        "pose": {"pose": {"position": {"x": x, "y": 0.0, "z": 0.0},
                          "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}},
        "twist": {"twist": {"linear": {"x": 0.0}, "angular": {"z": 0.0}}},
    }  # fmt: skip


async def test_the_embedded_bus_under_a_namespace_and_no_odometry_said_plainly(tmp_path):
    backend = start_backend("--namespace", "/robot2", "--no-sim")  # a robot whose odometry is not up yet
    link = RosLink("127.0.0.1", backend.bridge_port, namespace="/robot2", odom_topic="wheels/odom")
    app = make_app(settings(tmp_path), link, TrackerClient(backend.api), store=AnalyticsStore())
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            assert await until(pilot, lambda: link.state == CONNECTED, timeout=10)
            await pilot.press("i")
            assert await until(pilot, lambda: get_json(f"{backend.api}/api/health")["total_seen"] >= 1)
            # the command reached the namespaced tracker, and its report came back on the namespaced topic
            assert link.topic_stamped == "/robot2/stamped_cmd_vel"
            assert await until(pilot, lambda: link.telemetry.reports >= 1)
            said = "no odometry on /robot2/wheels/odom"
            assert await until(pilot, lambda: said in app.screen.query_one("#status").render().plain, 5)
            assert said in app.screen.query_one("#robot").render().plain
            assert app.screen.query_one("#status").has_class("alarm")
            async with aiohttp.ClientSession() as session:  # the robot's odometry comes up
                ws = await session.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}/")
                await ws.send_str(
                    '{"op":"advertise","topic":"/robot2/wheels/odom","type":"nav_msgs/msg/Odometry"}'
                )
                for i in range(20):
                    msg = {"op": "publish", "topic": "/robot2/wheels/odom", "msg": odometry(0.1 * i)}
                    await ws.send_str(json.dumps(msg))
                    await pilot.pause(0.05)
                    if link.telemetry.odom_count:
                        break
                shown = lambda: [app.screen.query_one(q).render().plain for q in ("#status", "#robot")]  # noqa: E731
                assert await until(pilot, lambda: all(said not in text for text in shown()))
                await ws.close()
            await pilot.press("ctrl+q")
    finally:
        link.close()
        backend.stop()
