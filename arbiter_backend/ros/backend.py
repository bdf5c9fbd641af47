"""``arbiter-backend --transport ros``: rclpy nodes on DDS, with our rosbridge endpoint and HTTP API.

Threads: the rclpy executor spins the nodes (tracker, simulator, bridge relay)
in its own thread; aiohttp (rosbridge WebSocket endpoint, tracker HTTP API) runs
on the asyncio loop in the main thread. The API reads the tracker under its lock
and never blocks the executor; the relay crosses threads with
``call_soon_threadsafe``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading

import rclpy
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from arbiter_core import topics

from .. import bridge
from ..config import BackendConfig
from ..servers import Servers
from . import topicwatch
from .autonomy import AutonomyNode
from .bus import RosBus
from .interfaces import RosInterfaces
from .nodes import SimulatorNode, TrackerNode
from .spin import spin_in_thread

log = logging.getLogger(__name__)

BRIDGE_NODE_NAME = topics.BRIDGE_NODE
EXECUTOR_WORKER = topicwatch.EXECUTOR_WORKER  # the worker that spins the tracker, simulator and relay


def _init(context: Context, args: list[str]) -> None:
    try:
        from rclpy.signals import SignalHandlerOptions

        # Our asyncio loop owns SIGINT/SIGTERM/SIGHUP, so shutdown is orderly (robot stop first).
        rclpy.init(args=args, context=context, signal_handler_options=SignalHandlerOptions.NO)
    except ImportError:  # an older rclpy without signal options
        rclpy.init(args=args, context=context)


class RosBackend(Servers):
    def __init__(self, config: BackendConfig, ros_args: list[str] | None = None) -> None:
        super().__init__(config)
        self.context = Context()
        _init(self.context, ["arbiter-backend", *(ros_args or [])])
        self.nodes: list[Node] = []
        try:
            self.tracker_node = TrackerNode(config, self.context)
            self.nodes.append(self.tracker_node)
            self.config = self.tracker_node.config  # parameters may override flags
            self.tracker = self.tracker_node.tracker
            if config.sim:
                self.nodes.append(SimulatorNode(self.config, self.context))
            self.autonomy_node: AutonomyNode | None = None
            if config.autonomy:
                self.autonomy_node = AutonomyNode(self.config, self.context)
                self.nodes.append(self.autonomy_node)
            self.sim_enabled = config.sim
            self.bridge_node: Node | None = None
            if config.bridge:
                # under --namespace as the other nodes: a client's relative names resolve there
                self.bridge_node = Node(BRIDGE_NODE_NAME, namespace=config.namespace, context=self.context)
                port = int(self.bridge_node.declare_parameter("port", config.bridge_port).value)
                self.config.bridge_port = port
                self.nodes.append(self.bridge_node)
            # in no executor: the monitor's own thread takes its messages (see ros/topicwatch.py)
            self.monitor_node = Node(
                topicwatch.NODE_NAME, context=self.context, start_parameter_services=False
            )
            self.topics = topicwatch.RosTopics(self.monitor_node, config.make_topic_watch(), self.supervisor)
        except BaseException:
            self._shutdown_ros()
            raise
        self.bus: RosBus | None = None
        self._watch: asyncio.Task[None] | None = None
        self.endpoint: bridge.RosbridgeEndpoint | None = None
        self.executor = SingleThreadedExecutor(context=self.context)
        for node in self.nodes:
            self.executor.add_node(node)
        self._thread: threading.Thread | None = None
        self._stop_spin = threading.Event()

    async def start(self) -> None:
        if self.bridge_node is not None:
            self.bus = RosBus(self.bridge_node, asyncio.get_running_loop())
            # a topic the relay reads is measured on its reader, not on a second one (ros/topicwatch.py)
            self.bus.tap, self.topics.relayed = self.topics.took, self.bus.relayed
            # services and actions across the bridge: the provided servers on a node of their own
            self.bus.interfaces = RosInterfaces(
                self.bridge_node, asyncio.get_running_loop(), self.context, self.supervisor
            )
            self.tracker_node.local_report = self.bus.deliver_local
            stamped = self.tracker_node.stamped_sub.topic_name
            self.bus.local_handlers[stamped] = self.tracker_node.on_local_command
            # names resolve as rclpy resolves them for the bridge node (remaps of __ns, __node included)
            node = self.bridge_node
            self.endpoint = self.config.make_endpoint(self.bus, node.get_namespace(), node.get_name())
            bus, beat = self.bus, self.supervisor.beat
            # QoS follows the publishers
            self._watch = self.supervisor.task("qos-follower", lambda: bus.watch_publishers(beat=beat))
        else:  # no endpoint (the stock rosbridge_server beside it): a bus on the tracker node all the same,
            # for a fleet console's stop (the action servers' cancels on the graph, zeros on a foreign
            # controller's cmd_vel)
            self.bus = RosBus(self.tracker_node, asyncio.get_running_loop())
        autonomy = self.autonomy_node.service if self.autonomy_node is not None else None
        await self.start_servers(self.endpoint, self.tracker, self.topics, autonomy)
        if self.bridge_node is not None:
            # as rosbridge_websocket does: the port bound (``port`` may be 0), for tools that ask the graph
            self.bridge_node.declare_parameter(
                "actual_port", self.bridge_port, ParameterDescriptor(read_only=True)
            )
        # the tracker's watchdog is one of its callbacks: while it is down the robot is held stopped
        self.supervisor.listen(EXECUTOR_WORKER, self.tracker_node.executor_changed)
        self._thread = spin_in_thread(
            self.executor, self.tracker_node, EXECUTOR_WORKER, self.supervisor, self._stop_spin, give_up=False
        )
        self.topics.start()

    def publish_zero(self) -> None:
        """One zero twist on the robot's command output now (a fleet console's stop)."""
        self.tracker_node.publish_zero()

    async def stop(self) -> None:
        if self._watch is not None:
            self._watch.cancel()
        await self.stop_servers(self.endpoint)
        if self.bus is not None:
            self.bus.close()
            if self.bus.interfaces is not None:
                self.bus.interfaces.close()
        self.topics.close()
        self._stop_spin.set()
        self.executor.shutdown(timeout_sec=2.0)
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._shutdown_ros()

    def _shutdown_ros(self) -> None:
        monitor = getattr(self, "monitor_node", None)
        for node in [*self.nodes, *([monitor] if monitor is not None else [])]:
            with contextlib.suppress(Exception):
                node.destroy_node()
        self.nodes.clear()
        with contextlib.suppress(Exception):
            self.context.try_shutdown()
