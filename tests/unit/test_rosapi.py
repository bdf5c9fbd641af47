"""rosapi answers from a graph (arbiter_backend.rosapi), on a graph written in the test."""

import pytest

from arbiter_backend.rosapi import handlers


class Graph:
    def node_names(self):
        return ["/arbiter_bridge", "/nav2/controller_server"]

    def topic_endpoints(self, topic):
        return {"/cmd_vel": (["/nav2/controller_server"], ["/arbiter_bridge", "/arbiter_bridge"])}.get(
            topic, ([], [])
        )

    def node_endpoints(self, node):
        return (["/odom"], ["/cmd_vel", "/plan"], ["/nav2/controller_server/get_parameters"])

    def service_names_and_types(self):
        return [("/nav2/controller_server/get_parameters", ["rcl_interfaces/srv/GetParameters"]),
                ("/reset", ["std_srvs/srv/Empty"])]  # fmt: skip


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


@pytest.mark.parametrize(
    ("service", "args", "said"),
    [
        ("/rosapi/publishers", {}, "args.topic"),
        ("/rosapi/node_details", {"node": 5}, "args.node"),
        ("/rosapi/node_details", {"node": "/ghost"}, "no node /ghost"),
        ("/rosapi/service_type", {"service": "/nope"}, "no service /nope"),
        ("/rosapi/services_for_type", [], "args.type"),
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
    with pytest.raises(ValueError, match="not exposed"):
        api["/rosapi/publishers"]({"topic": "/cmd_vel"})
    with pytest.raises(ValueError, match="no service /reset"):
        api["/rosapi/service_type"]({"service": "/reset"})
