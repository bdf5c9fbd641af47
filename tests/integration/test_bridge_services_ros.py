"""call_service to any service on the ROS graph (issue 34, item 1): answers, failures as ``result: false``
within the call's ``timeout``, never a hang, and the connection stays up."""

import json
import threading

import aiohttp
import pytest

from ..support.backend import start_backend
from ..support.ros import Peer, use_test_domain
from ..support.waits import async_poll, async_until

srv = pytest.importorskip("rcl_interfaces.srv")

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)


@pytest.fixture
def peer():
    p = Peer("arbiter_srv_peer")
    yield p
    p.close()


@pytest.fixture
def stuck_peer():
    p = Peer("arbiter_stuck_peer")  # its own executor thread: a stuck callback blocks only it
    yield p
    p.close()


@pytest.fixture
def ros_backend(peer):
    b = start_backend("--transport", "ros", "--no-sim", timeout=30)
    yield b
    b.stop()


async def call(ws, **frame):
    await ws.send_str(json.dumps({"op": "call_service", **frame}))
    while True:
        reply = json.loads((await ws.receive(timeout=15)).data)
        if reply.get("id") == frame.get("id"):
            return reply


async def test_call_service_reaches_any_service_and_fails_cleanly(peer, stuck_peer, ros_backend):
    peer.node.declare_parameter("speed", 1.5)
    release, called = threading.Event(), threading.Event()

    def stuck(request, response):  # a server that answers only when told to
        called.set()
        release.wait(20)
        return response

    stuck_peer.node.create_service(srv.GetParameterTypes, "/stuck", stuck)
    url = f"ws://127.0.0.1:{ros_backend.bridge_port}/"
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(url)
        name = "/arbiter_srv_peer/get_parameters"
        # the graph needs a moment to show the peer's services to the backend
        reply = await async_poll(
            lambda: call(ws, id="g", service=name, args={"names": ["speed"]}), lambda r: r["result"]
        )
        assert reply["result"] is True, reply
        assert reply["values"]["values"][0]["double_value"] == 1.5
        assert reply["service"] == name
        # args as a list in field order, as the protocol document has it
        reply = await call(ws, id="l", service=name, args=[["speed"]])
        assert reply["result"] is True and reply["values"]["values"][0]["double_value"] == 1.5

        reply = await call(ws, id="n", service="/no/such/service")
        assert reply == {
            "op": "service_response",
            "service": "/no/such/service",
            "id": "n",
            "result": False,
            "values": "Service /no/such/service does not exist",
        }
        reply = await call(ws, id="b", service=name, args={"nope": 1})
        assert reply["result"] is False and "unknown field" in reply["values"]

        # a server that does not answer: result false after the call's timeout, and the socket is free (the
        # timeout long enough that the other call, answered at once, comes first on a loaded machine);
        # first the graph must show the backend that server (else: "does not exist", at once)
        listed = await async_poll(
            lambda: call(ws, id="s", service="/rosapi/services"),
            lambda r: "/stuck" in r["values"]["services"],
        )
        assert "/stuck" in listed["values"]["services"], listed
        await ws.send_str(json.dumps({"op": "call_service", "id": "t", "service": "/stuck", "timeout": 3}))
        await ws.send_str(
            json.dumps({"op": "call_service", "id": "g2", "service": name, "args": {"names": []}})
        )
        first = json.loads((await ws.receive(timeout=15)).data)
        second = json.loads((await ws.receive(timeout=15)).data)
        assert first["id"] == "g2" and first["result"] is True  # not held behind the stuck call
        assert second["id"] == "t" and second["result"] is False
        assert second["values"] == "/stuck: no response within 3 s"
        assert called.is_set()  # it reached the server, which did not answer in time
        release.set()  # (before stuck_peer closes)

        await ws.send_str(json.dumps({"op": "call_service", "id": "x", "service": name, "timeout": -1}))
        bad = json.loads((await ws.receive(timeout=5)).data)
        assert bad["op"] == "status" and bad["id"] == "x" and "timeout" in bad["msg"]
        assert await async_until(lambda: not ws.closed)
        # rosapi still answers from the endpoint itself
        reply = await call(ws, id="r", service="/rosapi/topics")
        assert reply["result"] is True


async def test_rosapi_answers_from_the_live_graph(peer, ros_backend):
    """/rosapi/nodes, publishers, subscribers, node_details, services, service_type from the graph as it
    is (the peer appears with its topic and services); bad args are result false naming the field."""
    from std_msgs.msg import String

    peer.node.create_publisher(String, "/arbiter_graph_test", 10)
    url = f"ws://127.0.0.1:{ros_backend.bridge_port}/"
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(url)

        async def values(service, args=None):
            reply = await call(ws, id=service, service=service, args=args or {})
            assert reply["result"] is True, reply
            return reply["values"]

        async def peer_seen() -> bool:
            return "/arbiter_srv_peer" in (await values("/rosapi/nodes"))["nodes"]

        async def peer_publishes() -> bool:
            found = await values("/rosapi/publishers", {"topic": "/arbiter_graph_test"})
            return "/arbiter_srv_peer" in found["publishers"]

        assert await async_poll(peer_seen, bool, 15.0)  # the graph takes a moment to show the peer
        assert await async_poll(peer_publishes, bool, 15.0)
        details = await values("/rosapi/node_details", {"node": "/arbiter_srv_peer"})
        assert "/arbiter_graph_test" in details["publishing"]
        assert "/arbiter_srv_peer/get_parameters" in details["services"]
        assert "/arbiter_srv_peer/get_parameters" in (await values("/rosapi/services"))["services"]
        kind = await values("/rosapi/service_type", {"service": "/arbiter_srv_peer/get_parameters"})
        assert kind == {"type": "rcl_interfaces/srv/GetParameters"}
        assert (await values("/rosapi/get_time"))["time"]["sec"] > 1_700_000_000
        bad = await call(ws, id="bad", service="/rosapi/node_details", args={"node": 7})
        assert bad["result"] is False and "args.node" in bad["values"]
        await ws.close()


async def test_rosapi_parameters_and_raw_types_from_the_graph(peer, ros_backend):
    """get/set/has/delete_param and get_param_names as roslibjs calls them (``<node>:<param>``), over the
    peer's own parameter services; topics_and_raw_types with each type's full definition text."""
    from std_msgs.msg import String

    peer.node.declare_parameter("speed", 1.5)
    peer.node.create_publisher(String, "/arbiter_raw_types_test", 10)
    url = f"ws://127.0.0.1:{ros_backend.bridge_port}/"
    async with aiohttp.ClientSession() as session:
        ws = await session.ws_connect(url)
        reply = await async_poll(  # the graph needs a moment to show the peer's parameter services
            lambda: call(ws, id="n", service="/rosapi/get_param_names"),
            lambda r: "/arbiter_srv_peer:speed" in r["values"]["names"],
            15.0,
        )
        assert "/arbiter_srv_peer:speed" in reply["values"]["names"], reply

        async def param(service, **args):
            return await call(ws, id=service, service=f"/rosapi/{service}", args=args)

        assert (await param("get_param", name="/arbiter_srv_peer:speed"))["values"] == {"value": "1.5"}
        reply = await param("set_param", name="arbiter_srv_peer:speed", value="2.5")
        assert reply["result"] is True, reply
        assert peer.node.get_parameter("speed").value == 2.5  # set on the node itself
        assert (await param("has_param", name="/arbiter_srv_peer:speed"))["values"] == {"exists": True}
        assert (await param("has_param", name="/arbiter_srv_peer:nope"))["values"] == {"exists": False}
        reply = await param("get_param", name="/arbiter_srv_peer:nope", default_value="7")
        assert reply["values"] == {"value": "7"}  # rosapi's default for a parameter not set
        reply = await param("get_param", name="/no_such_node:x", default_value='"d"')
        assert reply["values"] == {"value": '"d"'}
        # what the node refuses is result false with its reason; bad args name the field
        reply = await param("set_param", name="/arbiter_srv_peer:speed", value='"fast"')
        assert reply["result"] is False and "refused" in reply["values"], reply
        reply = await param("delete_param", name="/arbiter_srv_peer:speed")  # declared: not undeclarable
        assert reply["result"] is False and "refused" in reply["values"], reply
        reply = await param("set_param", name="/arbiter_srv_peer:speed", value="not json")
        assert reply["result"] is False and "args.value must be JSON" in reply["values"]
        reply = await param("get_param", name="speed")
        assert reply["result"] is False and "<node_name>:<param_name>" in reply["values"]

        raw = (
            await async_poll(
                lambda: call(ws, id="raw", service="/rosapi/topics_and_raw_types"),
                lambda r: "/arbiter_raw_types_test" in r["values"]["topics"],
            )
        )["values"]
        i = raw["topics"].index("/arbiter_raw_types_test")
        assert raw["types"][i] == "std_msgs/msg/String"
        assert "string data" in raw["typedefs_full_text"][i]
        assert len(raw["topics"]) == len(raw["types"]) == len(raw["typedefs_full_text"])
        await ws.close()
