"""Services and actions both ways on ``--transport ros`` (issue 34, items 1-2): a WebSocket client's
``advertise_service`` / ``advertise_action`` is a real rclpy service / action server an rclpy node
calls; ``send_action_goal`` / ``cancel_action_goal`` reach an rclpy action server; failures end the
call or goal (never a hang) and bad input is a status error naming the id."""

import json
import threading
import time

import aiohttp
import pytest

from ..support.backend import start_backend
from ..support.ros import Peer, use_test_domain
from ..support.waits import async_until

std_srvs = pytest.importorskip("std_srvs.srv")
fib_action = pytest.importorskip("test_msgs.action")
from action_msgs.msg import GoalStatus  # noqa: E402  (after the skips: needs the ROS wheels)
from rclpy.action import ActionClient, ActionServer, CancelResponse  # noqa: E402

SetBool = std_srvs.SetBool
Fibonacci = fib_action.Fibonacci

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)


@pytest.fixture
def peer():
    p = Peer("arbiter_provided_peer", threads=4)
    yield p
    p.close()


@pytest.fixture
def ros_backend(peer):
    b = start_backend("--transport", "ros", "--no-sim", timeout=30)
    yield b
    b.stop()


async def frame_where(ws, want, limit: int = 50, timeout: float = 15.0):
    """The first frame ``want`` takes within ``timeout`` s in all (the endpoint's pings to a silent client
    would restart a per-receive timeout)."""
    deadline = time.monotonic() + timeout
    for _ in range(limit):
        msg = json.loads((await ws.receive(timeout=max(0.01, deadline - time.monotonic()))).data)
        if want(msg):
            return msg
    raise AssertionError("no such frame")


def op_is(op, **fields):
    return lambda m: m.get("op") == op and all(m.get(k) == v for k, v in fields.items())


async def test_a_client_provides_a_ros_service(peer, ros_backend):
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(f"ws://127.0.0.1:{ros_backend.bridge_port}/")
        await ws.send_json(
            {"op": "advertise_service", "service": "/arbiter_test/enable", "type": "std_srvs/SetBool"}
        )
        client = peer.node.create_client(SetBool, "/arbiter_test/enable")
        assert await async_until(client.service_is_ready, timeout=20)

        call = client.call_async(SetBool.Request(data=True))
        request = await frame_where(ws, op_is("call_service"))
        assert request == {
            "op": "call_service",
            "id": "service_request:/arbiter_test/enable:1",
            "service": "/arbiter_test/enable",
            "args": {"data": True},
        }
        await ws.send_json(
            {
                "op": "service_response",
                "service": "/arbiter_test/enable",
                "id": request["id"],
                "values": {"success": True, "message": "on"},
                "result": True,
            }
        )
        assert await async_until(call.done, timeout=10)
        assert call.result() == SetBool.Response(success=True, message="on")

        # result false, and a response that does not fit the type: the ROS caller gets the default
        # response (ROS 2 services have no error reply), at once; the provider hears what was wrong
        call = client.call_async(SetBool.Request(data=False))
        request = await frame_where(ws, op_is("call_service"))
        await ws.send_json(
            {
                "op": "service_response",
                "service": "/arbiter_test/enable",
                "id": request["id"],
                "values": "relay stuck",
                "result": False,
            }
        )
        assert await async_until(call.done, timeout=10)
        assert call.result() == SetBool.Response(success=False, message="")
        call = client.call_async(SetBool.Request(data=False))
        request = await frame_where(ws, op_is("call_service"))
        await ws.send_json(
            {
                "op": "service_response",
                "service": "/arbiter_test/enable",
                "id": request["id"],
                "values": {"success": "yes"},
                "result": True,
            }
        )
        status = await frame_where(ws, op_is("status"))
        assert status["id"] == request["id"] and "values.success" in status["msg"], status
        assert await async_until(call.done, timeout=10)
        assert call.result().success is False

        # the provider disconnects with a call pending: the ROS call ends, and the service goes away
        call = client.call_async(SetBool.Request(data=True))
        await frame_where(ws, op_is("call_service"))
        await ws.close()
        assert await async_until(call.done, timeout=10)
        assert call.result().success is False
        assert await async_until(lambda: not client.service_is_ready(), timeout=20)
        peer.node.destroy_client(client)


async def test_a_client_provides_a_ros_action(peer, ros_backend):
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(f"ws://127.0.0.1:{ros_backend.bridge_port}/")
        await ws.send_json(
            {"op": "advertise_action", "action": "/arbiter_test/fib", "type": "test_msgs/Fibonacci"}
        )
        client = ActionClient(peer.node, Fibonacci, "/arbiter_test/fib")
        assert await async_until(client.server_is_ready, timeout=20)

        feedback = []
        sent = client.send_goal_async(Fibonacci.Goal(order=3), feedback_callback=feedback.append)
        goal = await frame_where(ws, op_is("send_action_goal"))
        assert goal == {
            "op": "send_action_goal",
            "id": "action_goal:/arbiter_test/fib:1",
            "action": "/arbiter_test/fib",
            "action_type": "test_msgs/Fibonacci",  # as advertised
            "args": {"order": 3},
            "feedback": True,
        }
        assert await async_until(sent.done, timeout=10) and sent.result().accepted
        await ws.send_json(
            {
                "op": "action_feedback",
                "action": "/arbiter_test/fib",
                "id": goal["id"],
                "values": {"sequence": [0, 1, 1]},
            }
        )
        assert await async_until(lambda: feedback, timeout=10)
        assert list(feedback[0].feedback.sequence) == [0, 1, 1]
        result = sent.result().get_result_async()
        await ws.send_json(
            {
                "op": "action_result",
                "action": "/arbiter_test/fib",
                "id": goal["id"],
                "values": {"sequence": [0, 1, 1, 2]},
                "status": 4,
                "result": True,
            }
        )
        assert await async_until(result.done, timeout=10)
        assert result.result().status == GoalStatus.STATUS_SUCCEEDED
        assert list(result.result().result.sequence) == [0, 1, 1, 2]

        # a ROS cancel reaches the provider, which ends the goal as cancelled
        sent = client.send_goal_async(Fibonacci.Goal(order=30))
        goal = await frame_where(ws, op_is("send_action_goal"))
        assert await async_until(sent.done, timeout=10)
        sent.result().cancel_goal_async()
        cancel = await frame_where(ws, op_is("cancel_action_goal"))
        assert cancel == {"op": "cancel_action_goal", "id": goal["id"], "action": "/arbiter_test/fib"}
        result = sent.result().get_result_async()
        await ws.send_json(
            {
                "op": "action_result",
                "action": "/arbiter_test/fib",
                "id": goal["id"],
                "values": {"sequence": []},
                "status": 5,
                "result": True,
            }
        )
        assert await async_until(result.done, timeout=10)
        assert result.result().status == GoalStatus.STATUS_CANCELED

        # result false aborts the goal
        sent = client.send_goal_async(Fibonacci.Goal(order=2))
        goal = await frame_where(ws, op_is("send_action_goal"))
        assert await async_until(sent.done, timeout=10)
        result = sent.result().get_result_async()
        await ws.send_json(
            {
                "op": "action_result",
                "action": "/arbiter_test/fib",
                "id": goal["id"],
                "values": "motor fault",
                "result": False,
            }
        )
        assert await async_until(result.done, timeout=10)
        assert result.result().status == GoalStatus.STATUS_ABORTED
        await ws.send_json({"op": "unadvertise_action", "action": "/arbiter_test/fib"})
        await ws.send_json({"op": "unadvertise_action", "id": "u2", "action": "/arbiter_test/fib"})
        status = await frame_where(ws, op_is("status"))
        assert status["id"] == "u2" and "not advertised by this client" in status["msg"]
        await ws.close()
        client.destroy()


def fibonacci_server(peer, name: str, release: threading.Event) -> ActionServer:
    """An rclpy Fibonacci server: a feedback per step; long goals run until cancelled."""

    def execute(goal):
        seq = [0, 1]
        deadline = time.monotonic() + 20
        while len(seq) <= goal.request.order and time.monotonic() < deadline:
            if goal.is_cancel_requested:
                goal.canceled()
                return Fibonacci.Result(sequence=seq)
            seq.append(seq[-1] + seq[-2])
            goal.publish_feedback(Fibonacci.Feedback(sequence=seq))
            if goal.request.order > 10:
                release.wait(0.05)
        goal.succeed()
        return Fibonacci.Result(sequence=seq)

    return ActionServer(
        peer.node, Fibonacci, name, execute_callback=execute, cancel_callback=lambda _g: CancelResponse.ACCEPT
    )


async def test_send_action_goal_to_a_ros_action_server(peer, ros_backend):
    release = threading.Event()
    server = fibonacci_server(peer, "/arbiter_test/fib_server", release)
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(f"ws://127.0.0.1:{ros_backend.bridge_port}/")
        goal = {
            "op": "send_action_goal",
            "action": "/arbiter_test/fib_server",
            "action_type": "test_msgs/action/Fibonacci",
            "args": {"order": 4},
            "feedback": True,
        }
        # the graph takes a moment to show the server to the backend: until then, result false
        for attempt in range(40):
            gid = f"g{attempt}"
            await ws.send_json({**goal, "id": gid})
            first = await frame_where(ws, lambda m, gid=gid: m.get("id") == gid)
            if first["op"] == "action_feedback":
                break
            assert first["op"] == "action_result" and "not available" in first["values"], first
        frames = [first]
        while frames[-1]["op"] != "action_result":
            frames.append(await frame_where(ws, lambda m, gid=gid: m.get("id") == gid))
        # feedback in order and never after the result; the last may be lost to it (ROS carries them on
        # different channels; the endpoint does not send feedback once the result is out)
        seqs = [f["values"]["sequence"] for f in frames[:-1]]
        assert seqs and seqs == [[0, 1, 1], [0, 1, 1, 2], [0, 1, 1, 2, 3]][: len(seqs)], seqs
        assert frames[-1] == {
            "op": "action_result",
            "action": "/arbiter_test/fib_server",
            "id": gid,
            "values": {"sequence": [0, 1, 1, 2, 3]},
            "status": 4,
            "result": True,
        }

        # cancel_action_goal: the server sees the cancel and the goal ends as cancelled
        await ws.send_json({**goal, "id": "long", "args": {"order": 40}, "feedback": False})
        await ws.send_json({"op": "cancel_action_goal", "action": "/arbiter_test/fib_server", "id": "long"})
        result = await frame_where(ws, op_is("action_result", id="long"))
        assert result["status"] == GoalStatus.STATUS_CANCELED and result["result"] is True, result

        # no such server: result false within about a second, never a hang
        await ws.send_json({**goal, "id": "none", "action": "/arbiter_test/nobody"})
        result = await frame_where(ws, op_is("action_result", id="none"))
        assert result == {
            "op": "action_result",
            "action": "/arbiter_test/nobody",
            "id": "none",
            "status": 0,
            "result": False,
            "values": "Action /arbiter_test/nobody is not available",
        }
        # a goal that does not fit the type, an action type not installed: status errors naming the id
        await ws.send_json({**goal, "id": "bad", "args": {"order": "x"}})
        status = await frame_where(ws, op_is("status"))
        assert status["id"] == "bad" and "args.order" in status["msg"]
        await ws.send_json({**goal, "id": "bad2", "action_type": "nope_msgs/Fly"})
        status = await frame_where(ws, op_is("status"))
        assert status["id"] == "bad2" and "not installed" in status["msg"]
        await ws.send_json({"op": "advertise_service", "id": "bad3", "service": "/s", "type": "nope_srvs/X"})
        status = await frame_where(ws, op_is("status"))
        assert status["id"] == "bad3" and "not installed" in status["msg"]
        assert not ws.closed
        await ws.close()
    release.set()
    server.destroy()


async def test_a_goal_whose_server_leaves_ends(ros_backend):
    """An action server that leaves the graph while its goal runs: the goal ends, result false."""
    release = threading.Event()
    server_peer = Peer("arbiter_leaving_peer", threads=2)
    try:
        server = fibonacci_server(server_peer, "/arbiter_test/leaving", release)
        async with aiohttp.ClientSession() as session:
            ws = await session.ws_connect(f"ws://127.0.0.1:{ros_backend.bridge_port}/")
            goal = {
                "op": "send_action_goal",
                "action": "/arbiter_test/leaving",
                "action_type": "test_msgs/Fibonacci",
                "args": {"order": 40},
                "feedback": True,
            }
            for attempt in range(40):  # until the backend sees the server: the first feedback
                gid = f"l{attempt}"
                await ws.send_json({**goal, "id": gid})
                first = await frame_where(ws, lambda m, gid=gid: m.get("id") == gid)
                if first["op"] == "action_feedback":
                    break
            assert first["op"] == "action_feedback", first
            server.destroy()
            server_peer.node.destroy_node()  # the server leaves the graph mid-goal
            result = await frame_where(ws, op_is("action_result", id=gid), limit=500, timeout=20)
            assert result["result"] is False and "left before the goal ended" in result["values"], result
            await ws.close()
    finally:
        release.set()
        server_peer.executor.shutdown(timeout_sec=2)
        server_peer.context.try_shutdown()


def test_roslibpy_action_client_reaches_a_ros_action_server(peer, ros_backend):
    """roslibpy's own ActionClient (send_goal, feedback, result) against an rclpy action server."""
    import roslibpy

    from ..support.waits import wait_for

    release = threading.Event()
    server = fibonacci_server(peer, "/arbiter_test/fib_roslibpy", release)
    ros = roslibpy.Ros("127.0.0.1", ros_backend.bridge_port)
    ros.run(timeout=10)
    try:
        client = roslibpy.ActionClient(ros, "/arbiter_test/fib_roslibpy", "test_msgs/action/Fibonacci")
        results, feedback, errors = [], [], []
        for _ in range(40):  # until the backend sees the server (before: an error, "not available")
            errors.clear()
            client.send_goal(roslibpy.Goal({"order": 3}), results.append, feedback.append, errors.append)
            assert wait_for(lambda: results or errors, 10)
            if results:
                break
        assert results, errors
        assert list(results[0]["values"]["sequence"]) == [0, 1, 1, 2]
        assert results[0]["status"] == roslibpy.GoalStatus.SUCCEEDED
    finally:
        ros.close()
        release.set()
        server.destroy()
