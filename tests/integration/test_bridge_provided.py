"""Services and actions a WebSocket client provides, on the embedded transport (issue 34, items 1-2):
``advertise_service`` / ``service_response`` / ``unadvertise_service`` and ``advertise_action`` /
``action_feedback`` / ``action_result`` / ``unadvertise_action``, reached by another client's
``call_service`` and ``send_action_goal`` / ``cancel_action_goal``; bad input is a status error naming
the id, and the connection stays up."""

import json
import time

import pytest

from ..support.waits import async_until


async def frame_where(ws, want, limit: int = 50, timeout: float = 10.0):
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


@pytest.fixture
async def clients(server, session):
    url = f"ws://127.0.0.1:{server.bridge_port}/"
    provider = await session.ws_connect(url)
    caller = await session.ws_connect(url)
    yield provider, caller
    await caller.close()
    if not provider.closed:
        await provider.close()


async def test_a_client_provides_a_service_to_another(clients, session, server):
    provider, caller = clients
    await provider.send_json({"op": "advertise_service", "service": "/arm/home", "type": "std_srvs/SetBool"})
    await caller.send_json({"op": "call_service", "id": "c1", "service": "/arm/home", "args": {"data": True}})
    request = await frame_where(provider, op_is("call_service"))
    # the frame rosbridge_server sends a provider (its advertise_service tests compare it whole)
    assert request == {
        "op": "call_service",
        "id": "service_request:/arm/home:1",
        "service": "/arm/home",
        "args": {"data": True},
    }
    await provider.send_json(
        {
            "op": "service_response",
            "service": "/arm/home",
            "id": request["id"],
            "values": {"success": True, "message": "homed"},
            "result": True,
        }
    )
    reply = await frame_where(caller, op_is("service_response", id="c1"))
    assert reply == {
        "op": "service_response",
        "service": "/arm/home",
        "id": "c1",
        "result": True,
        "values": {"success": True, "message": "homed"},
    }

    # result false is passed through, with the provider's values
    await caller.send_json(
        {"op": "call_service", "id": "c2", "service": "/arm/home", "args": {"data": False}}
    )
    request = await frame_where(provider, op_is("call_service"))
    assert request["id"] == "service_request:/arm/home:2"
    await provider.send_json(
        {
            "op": "service_response",
            "service": "/arm/home",
            "id": request["id"],
            "values": "arm is stuck",
            "result": False,
        }
    )
    reply = await frame_where(caller, op_is("service_response", id="c2"))
    assert reply["result"] is False and reply["values"] == "arm is stuck"

    # a provider that does not answer: result false after the call's timeout, never a hang
    await caller.send_json({"op": "call_service", "id": "c3", "service": "/arm/home", "timeout": 0.3})
    late = await frame_where(provider, op_is("call_service"))
    reply = await frame_where(caller, op_is("service_response", id="c3"))
    assert reply["result"] is False and "no response from its provider within 0.3 s" in reply["values"]
    # ...and its answer after that is an error to the provider, naming the id
    await provider.send_json(
        {"op": "service_response", "service": "/arm/home", "id": late["id"], "values": {}, "result": True}
    )
    status = await frame_where(provider, op_is("status"))
    assert late["id"] in status["msg"] and "waiting" in status["msg"]

    # the provider disconnects with a call pending: the caller gets result false with why
    await caller.send_json({"op": "call_service", "id": "c4", "service": "/arm/home"})
    await frame_where(provider, op_is("call_service"))
    await provider.close()
    reply = await frame_where(caller, op_is("service_response", id="c4"))
    assert reply["result"] is False and "provider disconnected" in reply["values"]
    assert await async_until(lambda: "/arm/home" not in server.endpoint.provided_services)
    await caller.send_json({"op": "call_service", "id": "c5", "service": "/arm/home"})
    reply = await frame_where(caller, op_is("service_response", id="c5"))
    assert reply == {
        "op": "service_response",
        "service": "/arm/home",
        "id": "c5",
        "result": False,
        "values": "Service /arm/home does not exist",
    }


async def test_a_second_advertisement_replaces_the_first(clients, session, server):
    first, caller = clients
    second = await session.ws_connect(f"ws://127.0.0.1:{server.bridge_port}/")
    await first.send_json({"op": "advertise_service", "service": "/reset", "type": "std_srvs/srv/Trigger"})
    await caller.send_json({"op": "call_service", "id": "p", "service": "/reset"})
    await frame_where(first, op_is("call_service"))  # pending on the first provider
    await second.send_json({"op": "set_level", "level": "warning"})  # status warnings: on request only
    await second.send_json(
        {"op": "advertise_service", "id": "a2", "service": "/reset", "type": "std_srvs/Trigger"}
    )
    warning = await frame_where(second, op_is("status"))
    assert warning["level"] == "warning" and "replaced" in warning["msg"] and warning["id"] == "a2"
    reply = await frame_where(caller, op_is("service_response", id="p"))
    assert reply["result"] is False and "advertised again" in reply["values"]
    await caller.send_json({"op": "call_service", "id": "q", "service": "/reset"})
    request = await frame_where(second, op_is("call_service"))
    assert request["id"] == "service_request:/reset:1"  # numbered per advertisement
    await second.send_json(
        {
            "op": "service_response",
            "service": "/reset",
            "id": request["id"],
            "values": {"success": True, "message": "2"},
            "result": True,
        }
    )
    assert (await frame_where(caller, op_is("service_response", id="q")))["values"]["message"] == "2"
    # the replaced provider no longer owns it
    await first.send_json({"op": "unadvertise_service", "id": "u1", "service": "/reset"})
    status = await frame_where(first, op_is("status"))
    assert status["id"] == "u1" and "not advertised by this client" in status["msg"]
    await second.send_json({"op": "unadvertise_service", "service": "/reset"})
    assert await async_until(lambda: "/reset" not in server.endpoint.provided_services)
    await second.close()


BAD = [
    ({"op": "advertise_service", "id": "b1", "service": "/x"}, "missing field 'type'"),
    ({"op": "advertise_service", "id": "b2", "service": "/x", "type": "no type"}, "invalid srv type"),
    ({"op": "advertise_service", "id": "b3", "service": "x y", "type": "std_srvs/Empty"}, "invalid service"),
    ({"op": "advertise_service", "id": "b4", "service": "/rosapi/topics", "type": "a/B"}, "server's own"),
    ({"op": "unadvertise_service", "id": "b5", "service": "/never"}, "not advertised by this client"),
    ({"op": "service_response", "id": "b6", "service": "/never", "result": True}, "not advertised"),
    ({"op": "advertise_action", "id": "b7", "action": "/a", "type": "pkg/srv/X"}, "invalid action type"),
    ({"op": "send_action_goal", "id": "b8", "action": "/a"}, "missing field 'action_type'"),
    ({"op": "send_action_goal", "id": "b9", "action": 3, "action_type": "a/B"}, "wrong type"),
    ({"op": "cancel_action_goal", "id": "c1", "action": "/a"}, "no goal with id 'c1'"),
    ({"op": "cancel_action_goal", "action": "/a"}, "missing field 'id'"),
    ({"op": "action_feedback", "id": "c2", "action": "/a", "values": {}}, "not advertised by this client"),
    ({"op": "action_result", "id": "c3", "action": "/a", "result": True}, "not advertised by this client"),
    ({"op": "unadvertise_action", "id": "c4", "action": "/a"}, "not advertised by this client"),
]


async def test_bad_service_and_action_frames_are_status_errors(clients):
    provider, _caller = clients
    for frame, text in BAD:
        await provider.send_json(frame)
        status = await frame_where(provider, op_is("status"))
        assert text in status["msg"], (frame, status)
        assert status.get("id") == frame.get("id"), (frame, status)
    # after all that the connection works: the provider advertises and checks its own answers
    await provider.send_json({"op": "advertise_service", "service": "/s", "type": "std_srvs/Empty"})
    await provider.send_json(
        {"op": "service_response", "id": "nope", "service": "/s", "result": True, "values": []}
    )
    status = await frame_where(provider, op_is("status"))
    assert status["id"] == "nope" and "values must be an object" in status["msg"]
    await provider.send_json({"op": "service_response", "id": 7, "service": "/s", "result": True})
    status = await frame_where(provider, op_is("status"))
    assert status["id"] == 7 and "'id' has the wrong type" in status["msg"]
    await provider.send_json({"op": "service_response", "id": "n", "service": "/s", "result": "yes"})
    status = await frame_where(provider, op_is("status"))
    assert status["id"] == "n" and "'result' has the wrong type" in status["msg"]
    assert not provider.closed


async def test_a_client_provides_an_action_to_another(clients):
    provider, caller = clients
    await provider.send_json({"op": "advertise_action", "action": "/fib", "type": "test_msgs/Fibonacci"})
    await caller.send_json(
        {
            "op": "send_action_goal",
            "id": "g1",
            "action": "/fib",
            "action_type": "test_msgs/action/Fibonacci",
            "args": {"order": 3},
            "feedback": True,
        }
    )
    goal = await frame_where(provider, op_is("send_action_goal"))
    assert goal == {
        "op": "send_action_goal",
        "id": "action_goal:/fib:1",
        "action": "/fib",
        "action_type": "test_msgs/Fibonacci",  # as the provider wrote it, as rosbridge_server does
        "args": {"order": 3},
        "feedback": True,
    }
    for seq in ([0, 1], [0, 1, 1]):
        await provider.send_json(
            {"op": "action_feedback", "action": "/fib", "id": goal["id"], "values": {"sequence": seq}}
        )
        fb = await frame_where(caller, op_is("action_feedback"))
        assert fb == {"op": "action_feedback", "action": "/fib", "id": "g1", "values": {"sequence": seq}}
    await provider.send_json(
        {
            "op": "action_result",
            "action": "/fib",
            "id": goal["id"],
            "status": 4,
            "values": {"sequence": [0, 1, 1, 2]},
            "result": True,
        }
    )
    result = await frame_where(caller, op_is("action_result"))
    assert result == {
        "op": "action_result",
        "action": "/fib",
        "id": "g1",
        "status": 4,
        "result": True,
        "values": {"sequence": [0, 1, 1, 2]},
    }

    # cancel: the provider gets cancel_action_goal for its goal id and ends it as cancelled
    await caller.send_json(
        {
            "op": "send_action_goal",
            "id": "g2",
            "action": "/fib",
            "action_type": "test_msgs/Fibonacci",
            "args": {"order": 9},
        }
    )
    goal = await frame_where(provider, op_is("send_action_goal"))
    await caller.send_json(
        {"op": "send_action_goal", "id": "g2", "action": "/fib", "action_type": "test_msgs/Fibonacci"}
    )
    status = await frame_where(caller, op_is("status"))
    assert status["id"] == "g2" and "running already" in status["msg"]
    await caller.send_json({"op": "cancel_action_goal", "action": "/fib", "id": "g2"})
    cancel = await frame_where(provider, op_is("cancel_action_goal"))
    assert cancel == {"op": "cancel_action_goal", "id": goal["id"], "action": "/fib"}
    await provider.send_json(
        {
            "op": "action_result",
            "action": "/fib",
            "id": goal["id"],
            "status": 5,
            "values": {"sequence": []},
            "result": True,
        }
    )
    result = await frame_where(caller, op_is("action_result", id="g2"))
    assert result["status"] == 5 and result["result"] is True

    # result false aborts; a bad status is an error to the provider and the goal still runs
    await caller.send_json(
        {
            "op": "send_action_goal",
            "id": "g3",
            "action": "/fib",
            "action_type": "test_msgs/Fibonacci",
            "args": {"order": 1},
        }
    )
    goal = await frame_where(provider, op_is("send_action_goal"))
    await provider.send_json(
        {"op": "action_result", "action": "/fib", "id": goal["id"], "status": 2, "values": {}, "result": True}
    )
    status = await frame_where(provider, op_is("status"))
    assert "final GoalStatus" in status["msg"] and status["id"] == goal["id"]
    await provider.send_json(
        {"op": "action_result", "action": "/fib", "id": goal["id"], "values": "no", "result": False}
    )
    result = await frame_where(caller, op_is("action_result", id="g3"))
    assert result["result"] is False and result["status"] == 6 and result["values"] == "no"

    # the provider goes away with a goal running: the caller's goal ends, aborted, with why
    await caller.send_json(
        {
            "op": "send_action_goal",
            "id": "g4",
            "action": "/fib",
            "action_type": "test_msgs/Fibonacci",
            "args": {"order": 1},
        }
    )
    await frame_where(provider, op_is("send_action_goal"))
    await provider.close()
    result = await frame_where(caller, op_is("action_result", id="g4"))
    assert result["result"] is False and "provider disconnected" in result["values"]
    # nobody provides it now: on the embedded transport that is the end of it
    await caller.send_json(
        {"op": "send_action_goal", "id": "g5", "action": "/fib", "action_type": "test_msgs/Fibonacci"}
    )
    result = await frame_where(caller, op_is("action_result", id="g5"))
    assert result == {
        "op": "action_result",
        "action": "/fib",
        "id": "g5",
        "status": 0,
        "result": False,
        "values": "Action /fib does not exist",
    }


def test_roslibpy_provides_and_calls_a_service(backend):
    """roslibpy's own Service.advertise and Service.call, on two connections, through the endpoint."""
    import roslibpy

    from ..support.backend import wait_for

    provider, caller = roslibpy.Ros("127.0.0.1", backend.bridge_port), None
    provider.run(timeout=10)
    try:
        caller = roslibpy.Ros("127.0.0.1", backend.bridge_port)
        caller.run(timeout=10)

        def handle(request, response):
            response["success"] = request["data"]
            response["message"] = "flipped" if request["data"] else "kept"
            return True

        roslibpy.Service(provider, "/arbiter/flip", "std_srvs/SetBool").advertise(handle)
        service = roslibpy.Service(caller, "/arbiter/flip", "std_srvs/SetBool")
        answers: list = []

        def try_call() -> bool:  # until the advertisement has reached the endpoint
            service.call(roslibpy.ServiceRequest({"data": True}), answers.append, lambda _e: None)
            return bool(answers)

        assert wait_for(lambda: answers or try_call() or wait_for(lambda: answers, 0.3), timeout=10)
        assert dict(answers[0]) == {"success": True, "message": "flipped"}
        assert dict(service.call(roslibpy.ServiceRequest({"data": False}), timeout=10)) == {
            "success": False,
            "message": "kept",
        }
    finally:
        for ros in (provider, caller):
            if ros is not None:
                ros.close()


async def test_calls_under_way_per_client_are_bounded(clients):
    """A client cannot pile up calls without bound: past MAX_CALLS waiting, a call is a status error."""
    from arbiter_backend.bridge import MAX_CALLS

    provider, caller = clients
    await provider.send_json({"op": "advertise_service", "service": "/slow", "type": "std_srvs/Trigger"})
    await caller.send_json({"op": "call_service", "id": "first", "service": "/slow", "timeout": 30})
    await frame_where(provider, op_is("call_service"))  # advertised: the calls below reach it
    for i in range(MAX_CALLS - 1):
        await caller.send_json({"op": "call_service", "id": i, "service": "/slow", "timeout": 30})
    await caller.send_json({"op": "call_service", "id": "over", "service": "/slow"})
    status = await frame_where(caller, op_is("status"))
    assert status["id"] == "over" and "under way" in status["msg"]
    # one answered: room again
    await provider.send_json(
        {
            "op": "service_response",
            "service": "/slow",
            "values": {},
            "result": True,
            "id": "service_request:/slow:1",
        }
    )
    assert (await frame_where(caller, op_is("service_response", id="first")))["result"] is True
    await caller.send_json({"op": "call_service", "id": "again", "service": "/slow", "timeout": 0.2})
    reply = await frame_where(caller, op_is("service_response", id="again"))
    assert reply["result"] is False and "no response" in reply["values"]
