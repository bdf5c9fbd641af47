"""rosapi answers from a graph (arbiter_backend.rosapi), on a graph written in the test."""

import pytest

from arbiter_backend.bus import TopicBus
from arbiter_backend.rosapi import bus_handlers, handlers
from arbiter_core.msgtypes import TYPES
from arbiter_core.topics import resolve


class Graph:
    def node_names(self):
        return ["/arbiter_bridge", "/nav2/controller_server"]

    def topic_endpoints(self, topic):
        return {"/cmd_vel": (["/nav2/controller_server"], ["/arbiter_bridge", "/arbiter_bridge"])}.get(
            topic, ([], [])
        )

    def node_endpoints(self, node):
        return (["/odom"], ["/cmd_vel", "/plan"], ["/nav2/controller_server/get_parameters"])

    def node_services(self, node):
        return [("/nav2/controller_server/get_parameters", ["rcl_interfaces/srv/GetParameters"])] if (
            node == "/nav2/controller_server") else []  # fmt: skip

    def service_names_and_types(self):
        return [("/nav2/controller_server/get_parameters", ["rcl_interfaces/srv/GetParameters"]),
                ("/reset", ["std_srvs/srv/Empty"]),
                ("/follow_path/_action/send_goal", ["test_msgs/action/Fibonacci_SendGoal"])]  # fmt: skip

    def topic_names(self):
        return ["/cmd_vel", "/follow_path/_action/feedback", "/follow_path/_action/status",
                "/half/_action/status", "/_action/feedback", "/_action/status"]  # fmt: skip

    def distro(self):
        return "kilted"


API = handlers(Graph(), clock_ns=lambda: 1_800_000_000_250_000_000)


def test_each_rosapi_service_answers_in_rosapis_own_shape():
    assert API["/rosapi/nodes"]({}) == {"nodes": ["/arbiter_bridge", "/nav2/controller_server"]}
    assert API["/rosapi/publishers"]({"topic": "/cmd_vel"}) == {"publishers": ["/nav2/controller_server"]}
    assert API["/rosapi/subscribers"](["/cmd_vel"]) == {"subscribers": ["/arbiter_bridge"]}  # list args too
    assert API["/rosapi/node_details"]({"node": "/nav2/controller_server"}) == {
        "subscribing": ["/odom"], "publishing": ["/cmd_vel", "/plan"],
        "services": ["/nav2/controller_server/get_parameters"],
    }  # fmt: skip
    assert API["/rosapi/services"]({})["services"] == ["/nav2/controller_server/get_parameters", "/reset"]
    assert API["/rosapi/service_type"]({"service": "/reset"}) == {"type": "std_srvs/srv/Empty"}
    assert API["/rosapi/services_for_type"]({"type": "std_srvs/srv/Empty"}) == {"services": ["/reset"]}
    assert API["/rosapi/get_time"](None) == {"time": {"sec": 1_800_000_000, "nanosec": 250_000_000}}
    assert API["/rosapi/service_node"]({"service": "/nav2/controller_server/get_parameters"}) == {
        "node": "/nav2/controller_server"
    }
    assert API["/rosapi/service_node"]({"service": "/reset"}) == {"node": ""}  # nobody serves it
    # the stock node compares service_providers' "service" with each node's service TYPES
    assert API["/rosapi/service_providers"]({"service": "rcl_interfaces/srv/GetParameters"}) == {
        "providers": ["/nav2/controller_server"]
    }
    assert API["/rosapi/service_providers"]({"service": "/nav2/controller_server/get_parameters"}) == {
        "providers": []
    }
    # an action server shows both its feedback and status topics; hidden services are not listed
    assert API["/rosapi/action_servers"]({}) == {"action_servers": ["/follow_path"]}
    assert "/follow_path/_action/send_goal" not in API["/rosapi/services"]({})["services"]


def test_names_in_the_arguments_resolve_under_the_bridges_namespace():
    def in_nav2(name, what):
        return resolve(name, "/nav2", what=what, node="arbiter_bridge")

    api = handlers(Graph(), resolve=in_nav2)
    assert api["/rosapi/node_details"]({"node": "controller_server"})["publishing"] == ["/cmd_vel", "/plan"]
    assert api["/rosapi/service_node"]({"service": "controller_server/get_parameters"}) == {
        "node": "/nav2/controller_server"
    }
    assert API["/rosapi/publishers"]({"topic": "cmd_vel"}) == {"publishers": ["/nav2/controller_server"]}
    assert api["/rosapi/publishers"]({"topic": "cmd_vel"}) == {"publishers": []}  # /nav2/cmd_vel
    with pytest.raises(ValueError, match="1x"):
        api["/rosapi/publishers"]({"topic": "1x"})


def test_the_ros_version_is_2_and_the_distro_rclpys_unless_ros_distro_says(monkeypatch):
    monkeypatch.delenv("ROS_DISTRO", raising=False)
    assert API["/rosapi/get_ros_version"]({}) == {"version": 2, "distro": "kilted"}
    monkeypatch.setenv("ROS_DISTRO", "jazzy")
    assert API["/rosapi/get_ros_version"]({}) == {"version": 2, "distro": "jazzy"}


@pytest.mark.parametrize(
    ("service", "args", "said"),
    [
        ("/rosapi/publishers", {}, "args.topic"),
        ("/rosapi/node_details", {"node": 5}, "args.node"),
        ("/rosapi/node_details", {"node": "/ghost"}, "no node /ghost"),
        ("/rosapi/services_for_type", [], "args.type"),
        ("/rosapi/service_providers", {}, "args.service"),
    ],
)
def test_bad_arguments_say_which(service, args, said):
    with pytest.raises(ValueError, match=said):
        API[service](args)


def test_nothing_outside_what_the_server_exposes_appears():
    api = handlers(Graph(), topic_ok=lambda t: t != "/cmd_vel", service_ok=lambda s: s.startswith("/nav2/"))
    details = api["/rosapi/node_details"]({"node": "/nav2/controller_server"})
    assert (details["subscribing"], details["publishing"]) == (["/odom"], ["/plan"])
    assert details["services"] == ["/nav2/controller_server/get_parameters"]
    assert api["/rosapi/services"]({})["services"] == ["/nav2/controller_server/get_parameters"]
    # as the stock node: an empty answer, not an error
    assert api["/rosapi/publishers"]({"topic": "/cmd_vel"}) == {"publishers": []}
    assert api["/rosapi/service_type"]({"service": "/reset"}) == {"type": ""}
    assert api["/rosapi/service_node"]({"service": "/reset"}) == {"node": ""}


@pytest.mark.parametrize("type_name", sorted(TYPES))
def test_the_embedded_transports_message_details_are_the_ros_transports(type_name):
    """message_details on the embedded transport (the types it knows, from its own specs) gives what the
    ROS transport gives from the installed classes: the same TypeDefs, field by field."""
    ros_typedefs = pytest.importorskip("arbiter_backend.ros.typedefs")
    api = bus_handlers(TopicBus())
    assert api["/rosapi/message_details"]({"type": type_name}) == {
        "typedefs": ros_typedefs.message_typedefs(type_name)
    }
    assert api["/rosapi/message_details"]({"type": "sensor_msgs/msg/Image"}) == {"typedefs": []}
