"""The field's browser client against the backend: npm ``roslib`` 2.1.0 (roslibjs, pinned in
``tests/roslibjs``) calls each of its ``Ros`` helpers, then one publish/subscribe round, one service call
and one action goal round, on both transports. Each answer is compared with what rosbridge_suite's
rosapi answers, derived here on its own: on ``--transport ros`` from rclpy's view of the same graph and
the message classes (``tests/support/rosapi_expected.py``); on the embedded transport from the
documented embedded topics, and, for what has no meaning without a ROS graph, from what the backend
answers under the absolute name (roslibjs names rosapi's services without the leading slash).

The script runs once per transport (module-scoped); each helper is its own test, so a failure names it.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
from typing import Any

import aiohttp
import pytest

from ..support import rosapi_expected as expected
from ..support.backend import BackendProc, start_backend, wait_for
from ..support.node import roslibjs_ready, run_helpers

HELPERS = [
    "getTopics",
    "getServices",
    "getNodes",
    "getNodeDetails",
    "getParams",
    "getTopicType",
    "getServiceType",
    "getTopicsForType",
    "getServicesForType",
    "getMessageDetails",
    "getServiceRequestDetails",
    "getServiceResponseDetails",
    "getTopicsAndRawTypes",
    "getActionServers",
    "Topic.getPublishers",
    "Param.set",
    "Param.get",
]
# helper -> (the rosapi service it calls, its request, the part of the response its callback gets)
CALLS: dict[str, tuple[str, str, Any]] = {
    "getTopics": ("topics", "", None),
    "getServices": ("services", "", "services"),
    "getNodes": ("nodes", "", "nodes"),
    "getNodeDetails": ("node_details", "node", None),
    "getParams": ("get_param_names", "", "names"),
    "getTopicType": ("topic_type", "topic", "type"),
    "getServiceType": ("service_type", "service", "type"),
    "getTopicsForType": ("topics_for_type", "topic_type", "topics"),
    "getServicesForType": ("services_for_type", "service_type", "services"),
    "getMessageDetails": ("message_details", "message_type", "typedefs"),
    "getServiceRequestDetails": ("service_request_details", "service_type", None),
    "getServiceResponseDetails": ("service_response_details", "service_type", None),
    "getTopicsAndRawTypes": ("topics_and_raw_types", "", None),
    "getActionServers": ("action_servers", "", "action_servers"),
    "Topic.getPublishers": ("publishers", "topic", "publishers"),
    "Param.set": ("set_param", "", None),
    "Param.get": ("get_param", "", None),
}
REQUEST_FIELD = {"node": "node", "topic": "topic", "service": "service"}  # else the field is "type"

ROUND_TOPIC = "/arbiter_js/round"
SERVICE = "/arbiter_js/set_flag"
ACTION = "/arbiter_js/fibonacci"
FIBONACCI = "test_msgs/action/Fibonacci"
DETAILS_TYPE = "geometry_msgs/msg/TwistStamped"  # nested: Header, Time, Twist, Vector3
SERVICE_DETAILS_TYPE = "rcl_interfaces/srv/GetParameters"  # a sequence of messages in the response


@pytest.fixture(scope="module")
def node_bin() -> str:
    return roslibjs_ready()


def request_of(helper: str, plan: dict[str, Any]) -> dict[str, Any]:
    _, arg, _ = CALLS[helper]
    return {REQUEST_FIELD.get(arg, "type"): plan[arg]} if arg else {}


async def _absolute(port: int, plan: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Each helper's rosapi service called by its absolute name over a plain WebSocket."""
    out: dict[str, dict[str, Any]] = {}
    async with aiohttp.ClientSession() as session, session.ws_connect(f"ws://127.0.0.1:{port}/") as ws:
        for helper in HELPERS:
            if helper.startswith("Param."):  # a set and a get of one parameter: the test knows the answers
                continue
            service = "/rosapi/" + CALLS[helper][0]
            await ws.send_str(
                json.dumps(
                    {"op": "call_service", "id": helper, "service": service, "args": request_of(helper, plan)}
                )
            )
            while (reply := json.loads((await ws.receive(timeout=15)).data)).get("id") != helper:
                pass
            out[helper] = reply
    return out


def absolute_answers(backend: BackendProc, plan: dict[str, Any]) -> dict[str, dict[str, Any]]:
    return asyncio.run(_absolute(backend.bridge_port, plan))


def as_roslibjs(helper: str, reply: dict[str, Any]) -> dict[str, Any]:
    """An absolute-name reply as roslibjs's helper would hand it on: {"ok": ...} or {"error": ...}."""
    if not reply["result"]:
        return {"error": reply["values"]}
    pick = CALLS[helper][2]
    return {"ok": reply["values"][pick] if pick else reply["values"]}


def same_name(answer: dict[str, Any]) -> dict[str, Any]:
    """An error names the service as resolved or as given: "rosapi/x" and "/rosapi/x" are one name."""
    if "error" in answer:
        return {"error": answer["error"].replace(" rosapi/", " /rosapi/")}
    return answer


def assert_helper(helper: str, run: dict[str, Any]) -> None:
    got, want = same_name(run["out"]["helpers"][helper]), same_name(run["expected"][helper])
    assert got == want, f"{helper}: roslibjs got {got!r}, rosbridge_suite answers {want!r}"


# -- the embedded transport ------------------------------------------------------------------------------
EMBEDDED_TOPICS = {  # the embedded bus's topics (docs/ARCHITECTURE.md): the tracker and the simulated robot
    "/stamped_cmd_vel": "std_msgs/msg/String",
    "/cmd_vel_measured": "geometry_msgs/msg/Twist",
    "/latency_report": "std_msgs/msg/String",
    "/odom": "nav_msgs/msg/Odometry",
}


@pytest.fixture(scope="module")
def embedded(node_bin: str):
    backend = start_backend()
    try:
        plan = {
            "node": "/latency_tracker",
            "topic": "/odom",
            "topic_type": "nav_msgs/msg/Odometry",
            "service": SERVICE,
            "service_type": "std_srvs/srv/SetBool",
            "message_type": DETAILS_TYPE,
            "param": {"name": "/arbiter_js:speed", "value": 2.5},
            "pubsub": {
                "topic": ROUND_TOPIC,
                "type": "std_msgs/msg/String",
                "msg": {"data": "hello roslibjs"},
            },
            "service_call": {
                "name": SERVICE,
                "type": "std_srvs/srv/SetBool",
                "args": {"data": True},
                "provide": {"response": {"success": True}, "echo_into": "message"},
            },
            "action": {"name": ACTION, "type": FIBONACCI, "goal": {"order": 3}, "provide": True},
        }
        out = run_helpers(node_bin, f"ws://127.0.0.1:{backend.bridge_port}/", plan)
        absolute = absolute_answers(backend, plan)
    finally:
        backend.stop()
    # What has a meaning without a ROS graph: the bus's topics, and the parameters kept in memory (none set)
    want: dict[str, Any] = {
        "getTopicType": {"ok": "nav_msgs/msg/Odometry"},
        "getTopicsForType": {"ok": ["/odom"]},
        "getParams": {"ok": []},  # asked before Param.set
        "Param.get": {"ok": 2.5},  # after Param.set: the value set, as JSON, parsed by roslibjs
    }
    # the TypeDefs as rosapi builds them from the installed classes, where ROS is installed (else the
    # absolute name's answer below)
    with contextlib.suppress(ImportError):
        want["getMessageDetails"] = {"ok": expected.message_details(DETAILS_TYPE)}
    # the rest: what the same service answers under its absolute name ("does not exist": no ROS graph)
    for helper in HELPERS:
        if helper in absolute:
            want.setdefault(helper, as_roslibjs(helper, absolute[helper]))
    return {"out": out, "expected": want}


@pytest.mark.parametrize("helper", HELPERS)
def test_embedded_helper(embedded, helper):
    if helper == "Param.set":  # rosapi's SetParam response (empty, or "successful": true in later rosapi)
        got = embedded["out"]["helpers"][helper]
        assert "ok" in got, got
        return
    if helper == "getTopics":  # rosapi lists in the graph's order: compare topic -> type
        got = embedded["out"]["helpers"][helper]
        assert "ok" in got, got
        assert dict(zip(got["ok"]["topics"], got["ok"]["types"], strict=True)) == EMBEDDED_TOPICS
        return
    if helper == "getMessageDetails":  # the compared fields (rosapi_expected says why not examples)
        got = embedded["out"]["helpers"][helper]
        assert "ok" in got, got
        assert expected.compared(got["ok"]) == embedded["expected"][helper]["ok"]
        return
    assert_helper(helper, embedded)
    if helper not in EMBEDDED_ANSWERS:  # no meaning without a ROS graph: said so, as an unknown service
        assert "does not exist" in str(embedded["out"]["helpers"][helper].get("error")), helper


# what the embedded transport's rosapi answers (docs/rosbridge.md); any other helper's service does not exist
EMBEDDED_ANSWERS = {
    "getTopics", "getParams", "getTopicType", "getTopicsForType", "getMessageDetails", "Param.set",
    "Param.get",
}  # fmt: skip


def test_embedded_rounds(embedded):
    out = embedded["out"]
    assert out["roslib"] == "2.1.0"
    assert out["pubsub"] == {"ok": {"data": "hello roslibjs"}}
    assert out["service_call"] == {"ok": {"success": True, "message": '{"data":true}'}}
    assert out["action"] == {
        "ok": {"result": {"sequence": [0, 1, 2]}, "feedback": [{"sequence": [0]}, {"sequence": [0, 1]}]}
    }


# -- --transport ros ---------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def ros_graph(node_bin: str):
    """A peer with a topic it publishes, one it subscribes, a service, an action server and a parameter,
    the backend beside it; the script runs once, then the truth is read from the same graph."""
    from ..support import ros

    saved = ros.use_test_domain()
    next(saved)
    peer = ros.Peer("arbiter_js_peer", threads=3)
    backend = None
    try:
        node = peer.node
        node.declare_parameter("speed", 1.5)
        node.create_publisher(ros.String, "/arbiter_js/chatter", 10)
        received = peer.collect(ros.String, ROUND_TOPIC, lambda m: m.data)

        server = ros.serve_flag_and_fibonacci(node, SERVICE, ACTION)
        backend = start_backend("--transport", "ros", "--no-sim", timeout=30)
        plan = {
            "node": "/arbiter_js_peer",
            "topic": "/arbiter_js/chatter",
            "topic_type": "std_msgs/msg/String",
            "service": SERVICE,
            "service_type": SERVICE_DETAILS_TYPE,
            "message_type": DETAILS_TYPE,
            "param": {"name": "/arbiter_js_peer:speed", "value": 2.5},
            "pubsub": {"topic": ROUND_TOPIC, "type": "std_msgs/msg/String", "msg": {"data": "hello ROS"}},
            "service_call": {"name": SERVICE, "type": "std_srvs/srv/SetBool", "args": {"data": True}},
            "action": {"name": ACTION, "type": FIBONACCI, "goal": {"order": 5}},
        }
        truth = expected.GraphTruth(peer.node)

        # both sides see the whole graph before the script asks: the backend lists the peer's topic,
        # service and action topics (absolute names), the peer the backend's nodes
        def settled() -> bool:
            abs_ = absolute_answers(backend, plan)
            topics = abs_["getTopics"]["values"].get("topics", []) if abs_["getTopics"]["result"] else []
            services = (
                abs_["getServices"]["values"].get("services", []) if abs_["getServices"]["result"] else []
            )
            nodes = abs_["getNodes"]["values"].get("nodes", []) if abs_["getNodes"]["result"] else []
            return (
                {"/arbiter_js/chatter", ROUND_TOPIC} <= set(topics)
                and SERVICE in services
                and set(nodes) <= set(truth.nodes())
                and "/arbiter_js_peer" in nodes
            )

        assert wait_for(settled, 30, 0.5), "the backend and the peer did not see one graph in 30 s"
        want = {
            "getTopics": truth.topics(),
            "getServices": {"ok": sorted(truth.services())},
            "getNodes": {"ok": truth.nodes()},
            "getNodeDetails": {"ok": truth.node_details("/arbiter_js_peer")},
            "getParams": {"ok": sorted(truth.param_names())},
            "getTopicType": {"ok": "std_msgs/msg/String"},
            "getServiceType": {"ok": "std_srvs/srv/SetBool"},
            "getTopicsForType": {
                "ok": sorted(n for n, t in truth.topics().items() if t == "std_msgs/msg/String")
            },
            "getServicesForType": {
                "ok": sorted(n for n, t in truth.services().items() if t == SERVICE_DETAILS_TYPE)
            },
            "getMessageDetails": {"ok": expected.message_details(DETAILS_TYPE)},
            "getServiceRequestDetails": {
                "ok": {"typedefs": expected.service_details(SERVICE_DETAILS_TYPE, "Request")}
            },
            "getServiceResponseDetails": {
                "ok": {"typedefs": expected.service_details(SERVICE_DETAILS_TYPE, "Response")}
            },
            "getTopicsAndRawTypes": truth.topics(),
            "getActionServers": {"ok": expected.action_servers(list(truth.topics(include_hidden=True)))},
            "Topic.getPublishers": {"ok": truth.publishers("/arbiter_js/chatter")},
            "Param.set": None,  # "ok": the node took it (checked below on the node itself)
            "Param.get": {"ok": 2.5},
        }
        out = run_helpers(node_bin, f"ws://127.0.0.1:{backend.bridge_port}/", plan)
        got_on_ros = list(received)
        want["speed_on_the_node"] = node.get_parameter("speed").value
        yield {"out": out, "expected": want, "received": got_on_ros, "server": server}
    finally:
        if backend is not None:
            backend.stop()
        peer.close()
        next(saved, None)


LISTS = {"getServices", "getNodes", "getParams", "getTopicsForType", "getServicesForType", "getActionServers"}


@pytest.mark.parametrize("helper", HELPERS)
def test_ros_helper(ros_graph, helper):
    got = ros_graph["out"]["helpers"][helper]
    want = ros_graph["expected"][helper]
    assert "ok" in got, f"{helper}: {got}"
    answer = got["ok"]
    if helper == "Param.set":
        assert ros_graph["expected"]["speed_on_the_node"] == 2.5  # set on the rclpy node itself
        return
    if helper in ("getTopics", "getTopicsAndRawTypes"):  # the graph's order: compare topic -> type
        assert dict(zip(answer["topics"], answer["types"], strict=True)) == want
        if helper == "getTopicsAndRawTypes":
            for type_name, text in zip(answer["types"], answer["typedefs_full_text"], strict=True):
                own = text.split("\n=====")[0]
                fields = expected.typedef(expected._message_class(type_name))["fieldnames"]
                assert all(f" {f}" in own for f in fields), (type_name, text)
        return
    if helper in LISTS:  # the graph's order: compare sorted
        assert sorted(answer) == want["ok"], helper
        return
    if helper == "getNodeDetails":
        assert {k: sorted(v) for k, v in answer.items()} == want["ok"]
        return
    if helper == "getMessageDetails":
        assert expected.compared(answer) == want["ok"]
        assert ros_graph["out"]["decoded"] == {"ok": expected.decoded(DETAILS_TYPE)}
        return
    if helper in ("getServiceRequestDetails", "getServiceResponseDetails"):
        assert expected.compared(answer["typedefs"]) == want["ok"]["typedefs"]
        return
    assert got == want


def test_ros_rounds(ros_graph):
    out = ros_graph["out"]
    assert out["pubsub"] == {"ok": {"data": "hello ROS"}}
    assert "hello ROS" in ros_graph["received"]  # and it went out on the graph: the rclpy peer got it
    assert out["service_call"] == {"ok": {"success": True, "message": "flag set to True"}}
    assert "ok" in out["action"], out["action"]
    assert out["action"]["ok"]["result"] == {"sequence": [0, 1, 1, 2, 3, 5]}
    # feedback in order; ROS carries feedback and result apart, so the last feedback may come after the
    # result (then it is not delivered): a prefix, at least the first
    feedback = [f["sequence"] for f in out["action"]["ok"]["feedback"]]
    sent = [[0, 1, 1], [0, 1, 1, 2], [0, 1, 1, 2, 3], [0, 1, 1, 2, 3, 5]]
    assert feedback and feedback == sent[: len(feedback)], feedback
