"""rosapi's 24 services and a client's relative names, end to end: the real roslibpy client against
``arbiter-backend --transport ros`` beside an rclpy graph (a node with a topic, a subscription, a
service, an action server and a parameter; a second node in ``/robot2``), and against the embedded
transport. Each service is called as roslibjs 2.1.0 names it (``rosapi/topics``: relative) and as
roslibpy names it (``/rosapi/topics``); each answer is compared field by field with what the stock
rosapi node answers, the expected values taken from the graph as rclpy shows it to the peer (never
from the backend's code). Messages built from roslibpy's own ``Header`` and ``Time`` (``secs``,
``nsecs``: ROS 1's names, which rosbridge_suite takes) are published on both transports."""

import os
import threading
import time
from importlib import metadata

import pytest
import roslibpy
from roslibpy.ros2 import Header

from ..support.backend import start_backend
from ..support.ros import Peer, String, Twist, use_test_domain  # skips the module without rclpy
from ..support.waits import wait_for

rclpy = pytest.importorskip("rclpy")
ActionServer = pytest.importorskip("rclpy.action").ActionServer
get_action_names_and_types = pytest.importorskip("rclpy.action").get_action_names_and_types
PointStamped = pytest.importorskip("geometry_msgs.msg").PointStamped
Trigger = pytest.importorskip("std_srvs.srv").Trigger
Fibonacci = pytest.importorskip("test_msgs.action").Fibonacci

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)

# rosbridge_suite's rosapi_msgs/srv, all 24 (rosapi_node registers each as /rosapi/<name>)
ROSAPI = [
    "action_servers", "delete_param", "get_param", "get_param_names", "get_ros_version", "get_time",
    "has_param", "message_details", "node_details", "nodes", "publishers", "service_node",
    "service_providers", "service_request_details", "service_response_details", "service_type",
    "services", "services_for_type", "set_param", "subscribers", "topic_type", "topics",
    "topics_and_raw_types", "topics_for_type",
]  # fmt: skip
# what the embedded transport answers (no ROS graph: the rest "does not exist")
EMBEDDED = {"topics", "topic_type", "topics_for_type", "get_ros_version", "message_details", "get_param",
            "set_param", "has_param", "delete_param", "get_param_names"}  # fmt: skip
PEER = "/arbiter_rosapi_peer"

# The stock node's message_details for geometry_msgs/msg/Twist and service_request_details for
# std_srvs/srv/SetBool, as rosbridge_suite's rosapi (objectutils) gives them on these wheels, recorded;
# their constnames are the message's constants (stock also lists SLOT_TYPES and each field there)
TWIST = [
    {"type": "geometry_msgs/Twist", "fieldnames": ["linear", "angular"],
     "fieldtypes": ["geometry_msgs/Vector3", "geometry_msgs/Vector3"], "fieldarraylen": [-1, -1],
     "examples": ["{}", "{}"], "constnames": [], "constvalues": []},
    {"type": "geometry_msgs/Vector3", "fieldnames": ["x", "y", "z"], "fieldtypes": ["double"] * 3,
     "fieldarraylen": [-1] * 3, "examples": ["0.0"] * 3, "constnames": [], "constvalues": []},
]  # fmt: skip
SETBOOL_REQUEST = [
    {"type": "std_srvs/SetBool_Request", "fieldnames": ["data"], "fieldtypes": ["boolean"],
     "fieldarraylen": [-1], "examples": ["False"], "constnames": [], "constvalues": []},
]  # fmt: skip


def connect(port: int) -> roslibpy.Ros:
    ros = roslibpy.Ros("127.0.0.1", port)
    ros.run(timeout=10)
    return ros


def call(ros: roslibpy.Ros, name: str, args: dict | None = None) -> dict:
    """A call_service as roslibpy and roslibjs make it; roslibpy.core.ServiceException on result false."""
    service = roslibpy.Service(ros, name, "rosapi/" + name.rsplit("/", 1)[-1])
    return dict(service.call(roslibpy.ServiceRequest(args or {}), timeout=15))


class Graph:
    """The peer's graph: what the expected answers are read from (rclpy's view, not the backend's)."""

    def __init__(self) -> None:
        self.peer = Peer(PEER.lstrip("/"), threads=2)
        node = self.peer.node
        node.declare_parameter("speed", 1.5)
        self.chatter = node.create_publisher(String, "/arbiter_rosapi/chatter", 10)
        self.commands: list = []
        node.create_subscription(Twist, "/arbiter_rosapi/cmd", self.commands.append, 10)
        node.create_service(Trigger, "/arbiter_rosapi/trigger", self._trigger)
        self.fib = ActionServer(node, Fibonacci, "/arbiter_rosapi/fib", self._fibonacci)
        self.points: list = []
        node.create_subscription(PointStamped, "/arbiter_rosapi/points", self.points.append, 10)
        # a second node in a namespace, with its parameters settable from outside
        self.driver = rclpy.create_node(
            "driver", namespace="/robot2", context=self.peer.context, allow_undeclared_parameters=True
        )
        self.driver.create_service(Trigger, "reset", self._trigger)  # /robot2/reset
        self.peer.executor.add_node(self.driver)
        self.timer = node.create_timer(0.05, lambda: self.chatter.publish(String(data="hello")))

    @staticmethod
    def _trigger(request, response):
        response.success, response.message = True, "done"
        return response

    @staticmethod
    def _fibonacci(goal_handle):
        seq = [0, 1]
        for _ in range(goal_handle.request.order - 1):
            seq.append(seq[-1] + seq[-2])
        goal_handle.succeed()
        return Fibonacci.Result(sequence=seq)

    # -- the graph as rclpy shows it to the peer ---------------------------------------------------------
    def nodes(self) -> set[str]:
        names = self.peer.node.get_node_names_and_namespaces()
        return {f"{ns.rstrip('/')}/{n}" for n, ns in names if not n.startswith("_")}

    def services(self) -> dict[str, list[str]]:
        found = self.peer.node.get_service_names_and_types()
        return {s: list(ts) for s, ts in found if not any(p.startswith("_") for p in s.split("/"))}

    def node_services(self, node: str) -> dict[str, list[str]]:
        ns, _, name = node.rpartition("/")
        found = self.peer.node.get_service_names_and_types_by_node(name, ns or "/")
        return {s: list(ts) for s, ts in found}

    def close(self) -> None:
        self.driver.destroy_node()
        self.peer.close()


@pytest.fixture(scope="module")
def graph():
    g = Graph()
    yield g
    g.close()


@pytest.fixture(scope="module")
def ros_backend(graph):
    backend = start_backend("--transport", "ros", "--no-sim", timeout=30)
    yield backend
    backend.stop()


@pytest.fixture(scope="module")
def ros(ros_backend):
    client = connect(ros_backend.bridge_port)
    yield client
    client.close()


def both(ros: roslibpy.Ros, service: str, args: dict | None = None) -> dict:
    """The answer to rosapi/<service> (relative, as roslibjs 2.1.0 calls it), checked to be the answer to
    /rosapi/<service> (absolute, as roslibpy calls it)."""
    relative = call(ros, f"rosapi/{service}", args)
    absolute = call(ros, f"/rosapi/{service}", args)
    assert relative == absolute, (service, relative, absolute)
    return relative


def test_every_rosapi_service_answers_as_the_stock_node_by_relative_and_absolute_name(graph, ros):
    backend_nodes = {"/latency_tracker", "/arbiter_bridge"}
    # the graph takes a moment to show each side the other
    assert wait_for(
        lambda: backend_nodes <= graph.nodes() and graph.nodes() == set(both(ros, "nodes")["nodes"]), 20
    )
    assert wait_for(lambda: "/robot2/reset" in both(ros, "services")["services"], 15)
    assert wait_for(lambda: set(both(ros, "services")["services"]) == set(graph.services()), 15)
    peer = graph.peer.node
    details = {
        "subscribing": sorted(t for t, _ in peer.get_subscriber_names_and_types_by_node(PEER[1:], "/")
                              if "/_" not in t),
        "publishing": sorted(t for t, _ in peer.get_publisher_names_and_types_by_node(PEER[1:], "/")
                             if "/_" not in t),
        "services": sorted(s for s in graph.node_services(PEER) if "/_" not in s),
    }  # fmt: skip
    assert wait_for(lambda: both(ros, "node_details", {"node": PEER}) == details, 15)
    assert wait_for(lambda: "/arbiter_rosapi/fib" in both(ros, "action_servers")["action_servers"], 15)

    answers = {
        # topics: the peer's topics with their types
        "topics": both(ros, "topics"),
        "topic_type": both(ros, "topic_type", {"topic": "arbiter_rosapi/chatter"}),
        "topics_for_type": both(ros, "topics_for_type", {"type": "std_msgs/msg/String"}),
        "topics_and_raw_types": both(ros, "topics_and_raw_types"),
        "publishers": both(ros, "publishers", {"topic": "arbiter_rosapi/chatter"}),
        "subscribers": both(ros, "subscribers", {"topic": "/arbiter_rosapi/cmd"}),
        "node_details": both(ros, "node_details", {"node": "arbiter_rosapi_peer"}),
        "service_type": both(ros, "service_type", {"service": "arbiter_rosapi/trigger"}),
        "services_for_type": both(ros, "services_for_type", {"type": "std_srvs/srv/Trigger"}),
        "service_node": both(ros, "service_node", {"service": "robot2/reset"}),
        "service_providers": both(ros, "service_providers", {"service": "std_srvs/srv/Trigger"}),
        "action_servers": both(ros, "action_servers"),
        "message_details": both(ros, "message_details", {"type": "geometry_msgs/msg/Twist"}),
        "service_request_details": both(ros, "service_request_details", {"type": "std_srvs/srv/SetBool"}),
        "service_response_details": both(ros, "service_response_details", {"type": "std_srvs/Trigger"}),
        "get_ros_version": both(ros, "get_ros_version"),
        "get_param_names": both(ros, "get_param_names"),
        "get_param": both(ros, "get_param", {"name": "arbiter_rosapi_peer:speed", "default_value": ""}),
        "has_param": both(ros, "has_param", {"name": f"{PEER}:speed"}),
        "set_param": both(ros, "set_param", {"name": "robot2/driver:mode", "value": '"auto"'}),
        "delete_param": both(ros, "delete_param", {"name": "robot2/driver:mode"}),
        "nodes": both(ros, "nodes"),
        "services": both(ros, "services"),
    }
    before = time.time()
    answers["get_time"] = call(ros, "rosapi/get_time")
    absolute_time = call(ros, "/rosapi/get_time")
    assert sorted(answers) == ROSAPI  # all 24, each by both names

    topics = dict(zip(answers["topics"]["topics"], answers["topics"]["types"], strict=True))
    assert topics["/arbiter_rosapi/chatter"] == "std_msgs/msg/String"
    assert topics["/arbiter_rosapi/cmd"] == "geometry_msgs/msg/Twist"
    assert not any("/_" in t for t in topics)  # hidden (action) topics are not listed, as stock
    assert answers["topic_type"] == {"type": "std_msgs/msg/String"}
    assert "/arbiter_rosapi/chatter" in answers["topics_for_type"]["topics"]
    raw = answers["topics_and_raw_types"]
    assert raw["typedefs_full_text"][raw["topics"].index("/arbiter_rosapi/chatter")].startswith("# ")
    infos = graph.peer.node.get_publishers_info_by_topic("/arbiter_rosapi/chatter")
    assert (
        answers["publishers"]
        == {"publishers": sorted({f"/{i.node_name}" for i in infos})}
        == {"publishers": [PEER]}
    )
    assert PEER in answers["subscribers"]["subscribers"]
    assert answers["node_details"] == details
    assert answers["service_type"] == {"type": "std_srvs/srv/Trigger"}
    triggers = sorted(s for s, ts in graph.services().items() if ts == ["std_srvs/srv/Trigger"])
    assert (
        answers["services_for_type"]
        == {"services": triggers}
        == {"services": ["/arbiter_rosapi/trigger", "/robot2/reset"]}
    )
    assert answers["service_node"] == {"node": "/robot2/driver"}
    providers = sorted(
        n for n in graph.nodes() if ["std_srvs/srv/Trigger"] in graph.node_services(n).values()
    )
    assert answers["service_providers"] == {"providers": providers} == {"providers": [PEER, "/robot2/driver"]}
    actions = sorted(name for name, _types in get_action_names_and_types(peer))
    assert (
        answers["action_servers"]
        == {"action_servers": actions}
        == {"action_servers": ["/arbiter_rosapi/fib"]}
    )
    assert answers["message_details"] == {"typedefs": TWIST}
    assert answers["service_request_details"] == {"typedefs": SETBOOL_REQUEST}
    assert [t["fieldnames"] for t in answers["service_response_details"]["typedefs"]] == [
        ["success", "message"]
    ]
    rclpy_major = metadata.version("rclpy").split(".")[0]
    if os.environ.get("ROS_DISTRO") or rclpy_major == "9":  # the PyPI wheels here: kilted's rclpy 9.x
        distro = os.environ.get("ROS_DISTRO") or "kilted"
        assert answers["get_ros_version"] == {"version": 2, "distro": distro}
    assert f"{PEER}:speed" in answers["get_param_names"]["names"]
    assert answers["get_param"] == {"value": "1.5"}
    assert answers["has_param"] == {"exists": True}
    assert answers["set_param"] == answers["delete_param"] == {}
    stamp = answers["get_time"]["time"]
    assert abs(stamp["sec"] + stamp["nanosec"] / 1e9 - before) < 30 and set(absolute_time) == {"time"}


@pytest.mark.parametrize(
    ("service", "args", "expected"),
    [
        ("topic_type", {"topic": "no/such/topic"}, {"type": ""}),
        ("service_type", {"service": "no_such_service"}, {"type": ""}),
        ("service_node", {"service": "/no_such_service"}, {"node": ""}),
        ("publishers", {"topic": "/no/such/topic"}, {"publishers": []}),
        ("message_details", {"type": "no_such_pkg/msg/Thing"}, {"typedefs": []}),
    ],
)
def test_what_is_not_there_is_answered_empty_as_stock(ros, service, args, expected):
    assert both(ros, service, args) == expected


def test_every_op_resolves_a_relative_name_as_rosbridge(graph, ros):
    """subscribe, publish, call_service and send_action_goal with names without the leading slash: under
    the bridge node's namespace (the root here), as rosbridge_suite's node resolves them."""
    got, done = [], threading.Event()
    listener = roslibpy.Topic(ros, "arbiter_rosapi/chatter", "std_msgs/msg/String")
    listener.subscribe(got.append)
    assert wait_for(lambda: len(got) >= 2, 15), got
    listener.unsubscribe()
    assert got[0] == {"data": "hello"}

    cmd = roslibpy.Topic(ros, "arbiter_rosapi/cmd", "geometry_msgs/msg/Twist")
    cmd.advertise()
    assert wait_for(lambda: (cmd.publish(roslibpy.Message({"linear": {"x": 0.5}})), graph.commands)[1], 15)
    assert graph.commands[0].linear.x == 0.5
    cmd.unadvertise()

    trigger = roslibpy.Service(ros, "arbiter_rosapi/trigger", "std_srvs/srv/Trigger")
    assert dict(trigger.call(roslibpy.ServiceRequest({}), timeout=15)) == {"success": True, "message": "done"}

    # a service the client provides under a relative name: on the graph at /arbiter_rosapi/provided, and
    # its call_service frames carry the name as the client gave it (roslibpy dispatches by that name)
    def provide(request, response):
        response.update(success=True, message="from roslibpy")
        return True

    provided = roslibpy.Service(ros, "arbiter_rosapi/provided", "std_srvs/srv/Trigger")
    provided.advertise(provide)
    caller = graph.peer.node.create_client(Trigger, "/arbiter_rosapi/provided")
    assert caller.wait_for_service(timeout_sec=15)
    answer = caller.call_async(Trigger.Request())
    assert wait_for(answer.done, 15) and answer.result().message == "from roslibpy"
    provided.unadvertise()
    graph.peer.node.destroy_client(caller)

    results: list = []
    client = roslibpy.ActionClient(ros, "arbiter_rosapi/fib", "test_msgs/action/Fibonacci")
    client.send_goal(roslibpy.Goal({"order": 5}), lambda r: (results.append(r), done.set()), lambda f: None,
                     lambda e: (results.append(e), done.set()))  # fmt: skip
    assert done.wait(20), "no result"
    assert results[0]["values"]["sequence"] == [0, 1, 1, 2, 3, 5], results


def test_a_header_built_from_roslibpys_time_is_taken_as_rosbridge_takes_it(graph, ros):
    """roslibpy's ``Header(stamp=Time.now())`` sends ``secs``/``nsecs`` (its tests/ros2
    test_topic_with_header): the graph gets that stamp, a subscriber gets it back as ``sec``/``nanosec``."""
    echoed: list = []
    listener = roslibpy.Topic(ros, "/arbiter_rosapi/points", "geometry_msgs/msg/PointStamped")
    listener.subscribe(echoed.append)
    publisher = roslibpy.Topic(ros, "arbiter_rosapi/points", "geometry_msgs/msg/PointStamped")
    stamp = roslibpy.Time.now()
    msg = {"header": Header(stamp=stamp, frame_id="base"), "point": {"x": 0.0, "y": 1.0, "z": 2.0}}
    assert wait_for(lambda: (publisher.publish(roslibpy.Message(msg)), graph.points and echoed)[1], 15)
    publisher.unadvertise()
    listener.unsubscribe()
    got = graph.points[0]
    assert (got.header.stamp.sec, got.header.stamp.nanosec) == (stamp.secs, stamp.nsecs)
    assert got.header.frame_id == "base" and got.point.y == 1.0
    assert echoed[0]["header"] == {"stamp": {"sec": stamp.secs, "nanosec": stamp.nsecs}, "frame_id": "base"}


# -- the embedded transport ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def embedded():
    backend = start_backend("--namespace", "/robot2")
    client = connect(backend.bridge_port)
    yield client
    client.close()
    backend.stop()


def test_the_embedded_transport_answers_what_has_a_meaning_there_and_resolves_names(embedded):
    """Under --namespace /robot2: relative names resolve there (``odom`` is ``/robot2/odom``, the
    simulator's), so roslibjs's ``rosapi/topics`` is ``/robot2/rosapi/topics``, which does not exist (as
    on the stock server, whose rosapi services are absolute); ``/rosapi/...`` answers what has a meaning
    without a ROS graph, and the rest does not exist."""
    for name in ROSAPI:
        if name in EMBEDDED:
            args = {"name": "speed", "value": "1", "default_value": "", "topic": "odom",
                    "type": "nav_msgs/msg/Odometry"}  # fmt: skip
            assert isinstance(call(embedded, f"/rosapi/{name}", args), dict)
        else:
            with pytest.raises(
                roslibpy.core.ServiceException, match=f"Service /rosapi/{name} does not exist"
            ):
                call(embedded, f"/rosapi/{name}")
    with pytest.raises(roslibpy.core.ServiceException, match="Service /robot2/rosapi/topics does not exist"):
        call(embedded, "rosapi/topics")
    assert call(embedded, "/rosapi/topic_type", {"topic": "odom"}) == {"type": "nav_msgs/msg/Odometry"}
    assert call(embedded, "/rosapi/topics_for_type", {"type": "nav_msgs/msg/Odometry"}) == {
        "topics": ["/robot2/odom"]
    }
    assert call(embedded, "/rosapi/get_ros_version")["version"] == 2
    details = call(embedded, "/rosapi/message_details", {"type": "geometry_msgs/msg/Twist"})
    assert details == {"typedefs": TWIST}  # the stock node's answer, as on the ROS transport

    odom: list = []
    roslibpy.Topic(embedded, "odom", "nav_msgs/msg/Odometry").subscribe(odom.append)  # /robot2/odom
    assert wait_for(lambda: len(odom) > 1, 15)

    # roslibpy's Header(stamp=Time.now()) on a type the embedded transport knows
    echoed: list = []
    roslibpy.Topic(embedded, "/robot2/stamped", "geometry_msgs/msg/TwistStamped").subscribe(echoed.append)
    publisher = roslibpy.Topic(embedded, "stamped", "geometry_msgs/msg/TwistStamped")
    stamp = roslibpy.Time.now()
    msg = {"header": Header(stamp=stamp, frame_id="base"), "twist": {"linear": {"x": 1}}}
    assert wait_for(lambda: (publisher.publish(roslibpy.Message(msg)), echoed)[1], 15)
    assert echoed[0]["header"] == {"stamp": {"sec": stamp.secs, "nanosec": stamp.nsecs}, "frame_id": "base"}
    assert echoed[0]["twist"]["linear"] == {"x": 1.0, "y": 0.0, "z": 0.0}
