"""What a client may reach (--topics-glob, --services-glob, as rosbridge_server's topics_glob and
services_glob): outside them every op is a status error naming the id, nothing reaches the robot, and
rosapi lists nothing of it; the connection stays up."""

import json

from arbiter_backend.config import BackendConfig
from arbiter_backend.server import Backend


async def frames_until(ws, want, limit: int = 50):
    for _ in range(limit):
        msg = json.loads((await ws.receive(timeout=5)).data)
        if want(msg):
            return msg
    raise AssertionError("no such frame")


async def test_only_exposed_topics_and_services_are_reachable(session):
    backend = Backend(BackendConfig(bridge_port=0, api_port=0, topics_glob="/odom,/latency_*"))
    await backend.start()
    try:
        ws = await session.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}/")
        for op, extra in (("subscribe", {}), ("advertise", {"type": "std_msgs/String"})):
            await ws.send_json({"op": op, "id": f"{op}-1", "topic": "/stamped_cmd_vel", **extra})
            status = await frames_until(ws, lambda m: m.get("op") == "status")
            assert status["id"] == f"{op}-1" and "not exposed" in status["msg"], status
        await ws.send_json({"op": "publish", "id": "p-1", "topic": "/stamped_cmd_vel", "msg": {"data": "{}"}})
        status = await frames_until(ws, lambda m: m.get("op") == "status")
        assert status["id"] == "p-1" and "/stamped_cmd_vel is not exposed" in status["msg"]
        assert backend.tracker.health()["records_count"] == 0  # nothing reached the robot

        await ws.send_json({"op": "call_service", "id": "t", "service": "/rosapi/topics"})
        topics = (await frames_until(ws, lambda m: m.get("id") == "t"))["values"]["topics"]
        assert set(topics) == {"/odom", "/latency_report"}, topics
        await ws.send_json({"op": "call_service", "id": "ty", "service": "/rosapi/topic_type",
                            "args": {"topic": "/cmd_vel_measured"}})  # fmt: skip
        assert (await frames_until(ws, lambda m: m.get("id") == "ty"))["values"] == {"type": ""}

        await ws.send_json({"op": "subscribe", "id": "s", "topic": "/odom", "type": "nav_msgs/Odometry"})
        odom = await frames_until(ws, lambda m: m.get("op") == "publish")  # the connection is still up
        assert odom["topic"] == "/odom"
        await ws.close()
    finally:
        await backend.stop()


async def test_a_service_outside_the_glob_is_result_false(session):
    backend = Backend(BackendConfig(bridge_port=0, api_port=0, sim=False, services_glob="/arbiter/*"))
    await backend.start()
    try:
        ws = await session.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}/")
        await ws.send_json({"op": "call_service", "id": "r", "service": "/reset_robot"})
        reply = await frames_until(ws, lambda m: m.get("id") == "r")
        assert reply["result"] is False and "not exposed" in reply["values"]
        await ws.send_json({"op": "call_service", "id": "t", "service": "/rosapi/topics"})  # rosapi: always
        assert (await frames_until(ws, lambda m: m.get("id") == "t"))["result"] is True
        await ws.close()
    finally:
        await backend.stop()


async def test_actions_outside_the_glob_are_status_errors(session):
    """--actions-glob: a goal to an action outside it, or advertising one, is a status error naming the
    id; nothing reaches a provider. Inside it, goals reach the provider."""
    backend = Backend(BackendConfig(bridge_port=0, api_port=0, sim=False, actions_glob="/arm/*"))
    await backend.start()
    try:
        url = f"ws://127.0.0.1:{backend.bridge_port}/"
        provider, caller = await session.ws_connect(url), await session.ws_connect(url)
        await provider.send_json(
            {"op": "advertise_action", "id": "a1", "action": "/drive/go", "type": "test_msgs/Fibonacci"}
        )
        status = await frames_until(provider, lambda m: m.get("op") == "status")
        assert status["id"] == "a1" and "/drive/go is not exposed" in status["msg"]
        await caller.send_json(
            {
                "op": "send_action_goal",
                "id": "g1",
                "action": "/drive/go",
                "action_type": "test_msgs/Fibonacci",
                "args": {"order": 1},
            }
        )
        status = await frames_until(caller, lambda m: m.get("op") == "status")
        assert status["id"] == "g1" and "--actions-glob" in status["msg"]
        await provider.send_json(
            {"op": "advertise_action", "action": "/arm/home", "type": "test_msgs/Fibonacci"}
        )
        await caller.send_json(
            {
                "op": "send_action_goal",
                "id": "g2",
                "action": "/arm/home",
                "action_type": "test_msgs/Fibonacci",
                "args": {"order": 1},
            }
        )
        goal = await frames_until(provider, lambda m: m.get("op") == "send_action_goal")
        assert goal["action"] == "/arm/home"  # the only goal that reached the provider
        await provider.close()
        await caller.close()
    finally:
        await backend.stop()
