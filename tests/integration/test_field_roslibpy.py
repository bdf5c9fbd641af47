"""The installed roslibpy used the way its own ``tests/ros2`` use it, against the backend on both
transports: messages whose header is built from roslibpy's ``Header`` and ``Time`` (which send
``secs``/``nsecs``), its rosapi helpers, a service and a ROS 2 action. The cases are written here;
``test_backend_roslibpy.py`` covers the tracker's own topics and ``get_topics``/``get_topic_type``.

Expectations are rosbridge_suite's: rosapi's answers derived from rclpy's view of the same graph
(``tests/support/rosapi_expected.py``), the header read back by a real rclpy subscriber.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest
import roslibpy
from roslibpy.ros2 import Header

from ..support import rosapi_expected as expected
from ..support.backend import BackendProc, start_backend, wait_for

TOPIC = "/arbiter_py/stamped"
TYPE = "geometry_msgs/msg/TwistStamped"  # known to the embedded transport too
SERVICE = "/arbiter_py/set_flag"
ACTION = "/arbiter_py/fibonacci"


def connect(port: int) -> roslibpy.Ros:
    ros = roslibpy.Ros("127.0.0.1", port)
    ros.run(timeout=10)
    return ros


def stamped(i: int, stamp: roslibpy.Time) -> roslibpy.Message:
    return roslibpy.Message(
        {
            "header": Header(stamp=stamp, frame_id="base"),
            "twist": {"linear": {"x": 0.5 + i}, "angular": {"z": 0.25}},
        }
    )


def publish_until(publisher: roslibpy.Topic, make: Any, done: Any, timeout: float = 10) -> None:
    """Publish (a new message each 0.1 s) until ``done()``: the first may go before the far side matched."""
    deadline = time.monotonic() + timeout
    i = 0
    while not done() and time.monotonic() < deadline:
        publisher.publish(make(i))
        i += 1
        wait_for(done, 0.1)


# -- embedded --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def embedded():
    backend = start_backend()
    ros = connect(backend.bridge_port)
    yield backend, ros
    ros.close()
    backend.stop()


def test_embedded_header_from_roslibpy_time(embedded):
    """roslibpy's ``Header(stamp=Time.now())`` sends ``secs``/``nsecs``; rosbridge takes them for
    ``sec``/``nanosec``, and the subscriber gets ``sec``/``nanosec``."""
    _, ros = embedded
    got: list[dict] = []
    listener = roslibpy.Topic(ros, TOPIC, TYPE)
    listener.subscribe(got.append)
    publisher = roslibpy.Topic(ros, TOPIC, TYPE)
    stamp = roslibpy.Time.now()
    publish_until(publisher, lambda i: stamped(i, stamp), lambda: bool(got), 5)
    listener.unsubscribe()
    # (a server that refuses secs/nsecs answers a "status" op, which roslibpy only logs)
    assert got, "nothing arrived in 5 s"
    assert got[0]["header"] == {"stamp": {"sec": stamp.secs, "nanosec": stamp.nsecs}, "frame_id": "base"}
    assert got[0]["twist"]["linear"] == {"x": 0.5, "y": 0.0, "z": 0.0}  # missing fields defaulted


def test_embedded_rosapi_helpers(embedded):
    _, ros = embedded
    assert "/odom" in ros.get_topics()  # a list: roslibpy hands on the response's "topics"
    assert ros.get_topic_type("/odom") == "nav_msgs/msg/Odometry"
    assert ros.get_topics_for_type("nav_msgs/msg/Odometry") == ["/odom"]
    # parameters in memory on the embedded transport, as roslibpy's Param sets and reads them
    roslibpy.Param(ros, "/arbiter_py:speed").set(1.5)
    assert roslibpy.Param(ros, "/arbiter_py:speed").get() == 1.5
    assert "/arbiter_py:speed" in ros.get_params()


def test_embedded_service_provided_by_roslibpy(embedded):
    backend, ros = embedded
    server = connect(backend.bridge_port)
    try:
        service = roslibpy.Service(server, SERVICE, "std_srvs/srv/SetBool")

        def handler(request, response):
            response["success"] = request["data"]
            response["message"] = f"flag set to {request['data']}"
            return True

        service.advertise(handler)
        client = roslibpy.Service(ros, SERVICE, "std_srvs/srv/SetBool")
        answer: dict = {}

        def call() -> bool:
            try:
                answer.update(client.call(roslibpy.ServiceRequest({"data": True}), timeout=5))
            except roslibpy.core.ServiceException:
                return False  # not advertised yet: the advertise and this call race on two sockets
            return True

        assert wait_for(call, 10, 0.1)
        assert answer == {"success": True, "message": "flag set to True"}
    finally:
        server.close()


# -- --transport ros -------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def ros_side():
    from ..support import ros as rosmod

    domain = rosmod.use_test_domain()
    next(domain)
    peer = rosmod.Peer("arbiter_py_peer", threads=3)
    backend: BackendProc | None = None
    client: roslibpy.Ros | None = None
    try:
        node = peer.node
        node.declare_parameter("speed", 2.5)
        stamps = peer.collect(
            rosmod.TwistStamped,
            TOPIC,
            lambda m: (m.header.stamp.sec, m.header.stamp.nanosec, m.header.frame_id, m.twist.linear.x),
        )

        server = rosmod.serve_flag_and_fibonacci(node, SERVICE, ACTION)
        backend = start_backend("--transport", "ros", "--no-sim", timeout=30)
        client = connect(backend.bridge_port)
        truth = expected.GraphTruth(node)

        def settled() -> bool:
            try:
                nodes = client.get_nodes()
                services = client.get_services()
            except roslibpy.core.ServiceException:
                return False
            return "/arbiter_py_peer" in nodes and SERVICE in services and set(nodes) <= set(truth.nodes())

        assert wait_for(settled, 30, 0.5), "the backend and the peer did not see one graph in 30 s"
        yield {"ros": client, "peer": peer, "truth": truth, "stamps": stamps, "server": server}
    finally:
        if client is not None:
            client.close()
        if backend is not None:
            backend.stop()
        peer.close()
        next(domain, None)


def test_ros_header_from_roslibpy_time_reaches_rclpy(ros_side):
    """roslibpy's tests/ros2 ``test_topic_with_header``, read back by a real rclpy subscriber."""
    ros, stamps = ros_side["ros"], ros_side["stamps"]
    publisher = roslibpy.Topic(ros, TOPIC, TYPE)
    stamp = roslibpy.Time.now()
    publish_until(publisher, lambda i: stamped(i, stamp), lambda: bool(stamps), 10)
    assert stamps, "nothing reached rclpy in 10 s"
    assert stamps[0] == (stamp.secs, stamp.nsecs, "base", stamps[0][3])
    assert stamps[0][3] >= 0.5


def _node_details(ros: roslibpy.Ros) -> dict[str, list[str]]:
    details = ros.get_node_details("/arbiter_py_peer")
    return {k: sorted(details[k]) for k in ("subscribing", "publishing", "services")}


def _time_offset(ros: roslibpy.Ros) -> float:
    """The callback form: roslibpy's blocking ``get_time`` reads ROS 1's ``secs``/``nsecs``, a KeyError
    against rosbridge_suite on ROS 2 too, whose rosapi answers builtin_interfaces/Time."""
    box: dict = {}
    done = threading.Event()
    ros.get_time(lambda r: (box.update(r), done.set()), lambda e: (box.update(error=e), done.set()))
    assert done.wait(10) and "error" not in box, box
    return abs(box["time"]["sec"] + box["time"]["nanosec"] * 1e-9 - time.time())


# helper -> (what roslibpy answers, what rosapi answers on the same graph)
HELPERS: dict[str, tuple[Any, Any]] = {
    "get_topics": (lambda ros: sorted(ros.get_topics()), lambda truth: sorted(truth.topics())),
    "get_services": (lambda ros: sorted(ros.get_services()), lambda truth: sorted(truth.services())),
    "get_nodes": (lambda ros: sorted(ros.get_nodes()), lambda truth: truth.nodes()),
    "get_node_details": (_node_details, lambda truth: truth.node_details("/arbiter_py_peer")),
    "get_topic_type": (lambda ros: ros.get_topic_type(TOPIC), lambda truth: TYPE),
    "get_topics_for_type": (lambda ros: ros.get_topics_for_type(TYPE), lambda truth: [TOPIC]),
    "get_service_type": (lambda ros: ros.get_service_type(SERVICE), lambda truth: "std_srvs/srv/SetBool"),
    "get_services_for_type": (
        lambda ros: ros.get_services_for_type("std_srvs/srv/SetBool"),
        lambda truth: [SERVICE],
    ),
    "get_params": (lambda ros: sorted(ros.get_params()), lambda truth: sorted(truth.param_names())),
    "Param.get": (lambda ros: roslibpy.Param(ros, "/arbiter_py_peer:speed").get(), lambda truth: 2.5),
    "get_time": (lambda ros: _time_offset(ros) < 5, lambda truth: True),
}


@pytest.mark.parametrize("helper", list(HELPERS))
def test_ros_rosapi_helper_answers_as_rosapi(ros_side, helper):
    ask, truth = HELPERS[helper]
    assert ask(ros_side["ros"]) == truth(ros_side["truth"])


@pytest.mark.parametrize(
    "helper",
    [
        "get_message_details",
        "get_service_request_details",
        "get_service_response_details",
        "get_action_servers",
    ],
)
def test_ros_rosapi_details_and_action_servers(ros_side, helper):
    """The rosapi services roslibpy 2.1.0 has helpers for beyond the graph's lists."""
    ros, truth = ros_side["ros"], ros_side["truth"]
    if helper == "get_action_servers":
        box: dict = {}
        done = threading.Event()
        ros.get_action_servers(
            lambda r: (box.update(r), done.set()), lambda e: (box.update(error=e), done.set())
        )
        assert done.wait(10) and "error" not in box, box
        assert sorted(box["action_servers"]) == expected.action_servers(
            list(truth.topics(include_hidden=True))
        )
        return
    if helper == "get_message_details":
        answer = ros.get_message_details(TYPE)["typedefs"]
        want = expected.message_details(TYPE)
    else:
        part = "Request" if "request" in helper else "Response"
        answer = getattr(ros, helper)("std_srvs/srv/SetBool")["typedefs"]
        want = expected.service_details("std_srvs/srv/SetBool", part)
    assert expected.compared(answer) == want


def test_ros_service_and_action_rounds(ros_side):
    ros = ros_side["ros"]
    answer = roslibpy.Service(ros, SERVICE, "std_srvs/srv/SetBool").call(
        roslibpy.ServiceRequest({"data": True}), timeout=10
    )
    assert answer == {"success": True, "message": "flag set to True"}

    action = roslibpy.ActionClient(ros, ACTION, "test_msgs/action/Fibonacci")
    result: dict = {}
    feedback: list = []
    goal_id = action.send_goal(roslibpy.Goal({"order": 4}), result.update, feedback.append, result.update)
    action.wait_goal(goal_id, timeout=15)
    assert result.get("values") == {"sequence": [0, 1, 1, 2, 3]}, result
    sent = [[0, 1, 1], [0, 1, 1, 2], [0, 1, 1, 2, 3]]
    got = [f["sequence"] for f in feedback]
    assert got and got == sent[: len(got)], got
