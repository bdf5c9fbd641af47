"""The ros path's own faults, on real rclpy nodes (no executor spins them: the test is their executor).

The tracker while the executor that runs its watchdog is down (``nodes.TrackerNode.executor_changed``):
a zero at once, then every command from the relay's event loop forwarded as a zero until it runs again.
The topic monitor (``ros/topicwatch.RosTopics.take``) when one topic's messages cannot be taken: that
topic is listed with the reason, logged once, and the topics after it are taken all the same. rosapi on a
node that left the graph mid-call; the fleet stop's names in a remapped namespace."""

import asyncio
import logging

import pytest

from arbiter_backend.config import BackendConfig
from arbiter_backend.supervise import Supervisor, WorkerRecord
from arbiter_backend.topicwatch import TopicWatch
from arbiter_core import envelope, topics

from ..support.ros import Peer, String, Twist, use_test_domain
from ..support.waits import wait_for

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)


@pytest.fixture
def node_context():
    import rclpy
    from rclpy.context import Context

    from ..support.ros import domain

    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain())
    yield ctx
    ctx.try_shutdown()


@pytest.fixture
def peer():
    p = Peer("arbiter_faults_peer")
    yield p
    p.close()


def test_while_the_executor_is_down_the_tracker_sends_a_zero_and_forwards_zeros(node_context, peer):
    from arbiter_backend.ros.nodes import TrackerNode

    node = TrackerNode(BackendConfig(), node_context)
    try:
        got = peer.collect(Twist, "/" + topics.MEASURED, lambda m: round(m.linear.x, 3))
        pub = node.measured_pub
        # both ends matched: a message before then is lost
        assert wait_for(lambda: peer.matched("/" + topics.MEASURED) == pub.get_subscription_count() == 1, 10)
        node.on_local_command(envelope.build(0.3, 0.0, seq=1))
        assert wait_for(lambda: got and got[-1] > 0, 5), got
        w = WorkerRecord("rclpy-executor")
        w.begin(0.0)
        w.fail(RuntimeError("a callback raised"), 0.0, 0.0)  # restarting: its watchdog does not run
        node.executor_changed(w)
        assert wait_for(lambda: got[-1] == 0.0, 5), got  # at once, not after cmd_timeout
        n = len(got)
        node.on_local_command(envelope.build(0.3, 0.0, seq=2))
        assert wait_for(lambda: len(got) > n, 5) and got[-1] == 0.0, got  # held: forwarded as a zero
        w.beat(1.0, 1.0)  # its first beat after the restart: running
        node.executor_changed(w)
        node.on_local_command(envelope.build(0.3, 0.0, seq=3))
        assert wait_for(lambda: got[-1] > 0, 5), got  # drives again
    finally:
        node.destroy_node()


def test_a_topic_that_cannot_be_taken_is_listed_once_and_the_others_are_taken(node_context, peer, caplog):
    from rclpy.node import Node

    from arbiter_backend.ros.topicwatch import RosTopics

    monitor = Node("arbiter_faults_monitor", context=node_context, start_parameter_services=False)
    watch = TopicWatch()
    rt = RosTopics(monitor, watch, Supervisor(faults={}))
    pubs = {t: peer.node.create_publisher(String, t, 10) for t in ("/arbiter_test/a", "/arbiter_test/b")}
    try:
        assert wait_for(lambda: (rt.look(), set(pubs) <= set(rt._subs))[1], 10), rt._subs
        assert wait_for(lambda: all(monitor.count_publishers(t) == 1 for t in pubs), 10)
        broken = "/arbiter_test/a"
        monitor.destroy_subscription(rt._subs[broken][2])  # its handle goes away under the monitor
        rt._subs = {broken: rt._subs[broken], **rt._subs}  # the broken one first: the others after it

        def taken() -> int:
            pubs["/arbiter_test/b"].publish(String(data="x"))
            pubs[broken].publish(String(data="x"))
            with caplog.at_level(logging.WARNING):
                rt.take()
                rt.look()
            row = {t["name"]: t for t in watch.answer()["topics"]}["/arbiter_test/b"]
            return int(row["total"])

        assert wait_for(lambda: taken() >= 3, 10)
        rows = {t["name"]: t for t in watch.answer()["topics"]}
        assert rows[broken]["note"].startswith("cannot be read here: "), rows[broken]
        warned = [r for r in caplog.records if broken in r.getMessage()]
        assert len(warned) == 1, [r.getMessage() for r in warned]
    finally:
        rt.close()
        monitor.destroy_node()


def test_a_node_that_left_the_graph_has_no_endpoints_not_an_error(node_context):
    """rosapi's node_details on a node that left between the listing and the call: empty lists, as the
    stock node answers, not rclpy's NodeNameNonExistentError out of the handler."""
    from rclpy.node import Node

    from arbiter_backend.ros.graph import RosGraph

    node = Node("arbiter_faults_graph", context=node_context, start_parameter_services=False)
    try:
        graph = RosGraph(node, asyncio.new_event_loop(), list)
        assert graph.node_endpoints("/arbiter_left_already") == ([], [], [])
        assert graph.node_services("/arbiter_left_already") == []
    finally:
        node.destroy_node()


def test_the_fleet_stop_resolves_its_names_in_the_namespace_a_remap_gave_the_tracker():
    """``--ros-args -r __ns:=/robot1``: the fleet stop's ``cmd_vel`` and Nav2 actions are the robot's
    (``/robot1/cmd_vel``), as the tracker node resolves its own names, not ``--namespace``'s root."""
    from arbiter_backend.fleet import sources_of
    from arbiter_backend.ros.backend import RosBackend

    backend = RosBackend(
        BackendConfig(sim=False, bridge=False, api_port=0), ["--ros-args", "-r", "__ns:=/robot1"]
    )
    try:
        src = sources_of(backend)
        assert (src.cmd_topic, src.namespace) == ("/robot1/cmd_vel", "/robot1")
    finally:
        backend._shutdown_ros()
