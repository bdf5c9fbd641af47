"""A ROS 2 graph shaped like a real robot's, for the tests and the benchmarks: run it as a program.

Laid out like a Nav2 bringup on a differential-drive base, with the types the PyPI ROS wheels carry
(``test_msgs/action/Fibonacci`` standing in for ``nav2_msgs``' actions, ``std_srvs/srv/Trigger`` for
its lifecycle manager's services). Everything Nav2 puts on the graph that is not a plain topic is here:

- lifecycle nodes (rclpy's ``LifecycleNode``: ``get_state``, ``change_state``, ``transition_event``…),
  configured and activated as Nav2's lifecycle manager does;
- action servers (``navigate_to_pose``, ``follow_path``, ``compute_path_to_pose``, ``spin``, ``backup``,
  ``drive_on_heading``, ``follow_waypoints``), so ``_action/feedback`` and ``_action/status`` topics and
  the ``send_goal``/``cancel_goal``/``get_result`` services;
- service introspection on (kilted's ``configure_introspection``, contents): the lifecycle manager's
  ``is_active`` is called twice a second by an "rviz" client, both ends introspected, so
  ``/lifecycle_manager_navigation/is_active/_service_event`` carries ``std_srvs/srv/Trigger_Event``;
- Nav2's topics at their usual rates (``/scan``, ``/imu/data``, ``/joint_states``, ``/plan``,
  ``/local_plan``, ``/cmd_vel``, ``/amcl_pose``, ``/particle_cloud``, costmaps, footprints, markers,
  ``/diagnostics``, a latched ``/map`` and ``/robot_description``), ``--hub N`` further topics of a
  sensor hub at 1-20 Hz, and a second robot under ``/robot2``;
- two waves: the behavior server, the waypoint follower, the second robot and half the hub come up
  ``--wave2-after`` seconds after the rest, as nodes of a real bringup come up late.

``/odom`` is not published here: the backend under test (``--transport ros``) simulates the base. The
``follow_path`` server is a controller: while its goal is active it follows a straight plan to the goal
from ``/odom`` and drives the base on ``--drive-topic`` (what the backend's simulator takes), says its
command on ``/cmd_vel`` (``TwistStamped``, as kilted's Nav2 does) and publishes ``/plan``, a
``/goal_pose`` and feedback; a cancel ends it at once, with one zero command.

Every publish is timed (``CLOCK_MONOTONIC``, one clock for every process of the machine), so the
truth of each rate is what was really sent, however late a loaded machine ran the timers.

Standard input, one command a line: ``goal X Y`` (the navigator sends a ``follow_path`` goal),
``dump`` (prints one JSON line: ``times`` per topic, ``goals`` with how each ended, ``types`` per topic,
``services``, ``actions``), ``quit``. Standard output: ``ready 1``, ``ready 2`` as the waves come up.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import (
    Point32,
    PolygonStamped,
    PoseArray,
    PoseStamped,
    PoseWithCovarianceStamped,
    Twist,
    TwistStamped,
)
from nav_msgs.msg import OccupancyGrid, Odometry, Path
from rclpy.action import ActionClient, ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn
from rclpy.node import Node
from rclpy.qos import (
    DurabilityPolicy,
    QoSProfile,
    ReliabilityPolicy,
    qos_profile_sensor_data,
    qos_profile_services_default,
)
from rclpy.service_introspection import ServiceIntrospectionState
from sensor_msgs.msg import Imu, JointState, LaserScan
from std_msgs.msg import Float32, String
from std_srvs.srv import Trigger
from test_msgs.action import Fibonacci
from visualization_msgs.msg import Marker, MarkerArray

LATCHED = QoSProfile(
    depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
)
HUB_RATES = (1.0, 2.0, 5.0, 10.0, 20.0)

# Nav2's lifecycle nodes, their actions and what they publish: (topic, type, Hz, factory, QoS)
ACTIONS = {
    "bt_navigator": ("navigate_to_pose",),
    "controller_server": ("follow_path",),
    "planner_server": ("compute_path_to_pose",),
    "behavior_server": ("spin", "backup", "drive_on_heading"),
    "waypoint_follower": ("follow_waypoints",),
}
WAVE2_NODES = ("behavior_server", "waypoint_follower")


def _scan() -> LaserScan:
    m = LaserScan()
    m.header.frame_id = "base_scan"
    m.angle_min, m.angle_max, m.angle_increment = -math.pi, math.pi, 2 * math.pi / 360
    m.range_min, m.range_max = 0.12, 3.5
    m.ranges = [1.5] * 360
    return m


def _grid(side: int) -> OccupancyGrid:
    m = OccupancyGrid()
    m.header.frame_id = "map"
    m.info.resolution, m.info.width, m.info.height = 0.05, side, side
    m.data = [0] * (side * side)
    return m


def _markers() -> MarkerArray:
    out = MarkerArray()
    for i in range(10):
        mk = Marker()
        mk.header.frame_id, mk.ns, mk.id, mk.type = "map", "waypoints", i, Marker.SPHERE
        mk.pose.position.x, mk.pose.orientation.w = float(i), 1.0
        mk.scale.x = mk.scale.y = mk.scale.z = 0.1
        out.markers.append(mk)
    return out


def _diagnostics() -> DiagnosticArray:
    out = DiagnosticArray()
    for name in ("battery", "motors", "lidar", "imu"):
        st = DiagnosticStatus()
        st.name, st.level, st.message, st.hardware_id = name, DiagnosticStatus.OK, "ok", "base"
        out.status.append(st)
    return out


def _footprint() -> PolygonStamped:
    m = PolygonStamped()
    m.header.frame_id = "odom"
    m.polygon.points = [
        Point32(x=x, y=y) for x, y in ((0.2, 0.15), (0.2, -0.15), (-0.2, -0.15), (-0.2, 0.15))
    ]
    return m


def _joints() -> JointState:
    m = JointState()
    m.name, m.position, m.velocity = ["wheel_left_joint", "wheel_right_joint"], [0.0, 0.0], [0.0, 0.0]
    return m


def _particles() -> PoseArray:
    m = PoseArray()
    m.header.frame_id = "map"
    m.poses = [PoseStamped().pose for _ in range(200)]
    return m


class Graph:
    """The whole bringup, spun by one multi-threaded executor; every publish timed in ``times``."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.executor = MultiThreadedExecutor(num_threads=4)
        self.nodes: dict[str, Node] = {}
        self.times: dict[str, list[float]] = {}
        self.types: dict[str, str] = {}
        self.goals: list[dict[str, Any]] = []
        self.lock = threading.Lock()
        self.pose = (0.0, 0.0, 0.0)
        self.pose2 = (0.0, 0.0, 0.0)
        self.servers: list[ActionServer] = []
        self.keep: list[Any] = []  # timers, services, clients: alive as long as the graph
        self.closing = threading.Event()  # a goal still running at ``quit`` aborts

    # -- building blocks ---------------------------------------------------------------------------
    def node(self, name: str, namespace: str = "", lifecycle: bool = False) -> Node:
        n: Node = LifecycleNode(name, namespace=namespace) if lifecycle else Node(name, namespace=namespace)
        self.nodes[f"{namespace}/{name}"] = n
        self.executor.add_node(n)
        return n

    def periodic(
        self, node: Node, topic: str, kind: Any, hz: float, make: Callable[[], Any], qos: Any = 10,
        stamp: bool = False,
    ) -> None:  # fmt: skip
        """``topic`` published at ``hz``, each publish timed; ``stamp``: header.stamp set to now."""
        pub = node.create_publisher(kind, topic, qos)
        name = pub.topic_name
        msg = make()
        self.times[name] = []
        self.types[name] = _type_name(kind)

        def tick() -> None:
            if stamp:
                msg.header.stamp = node.get_clock().now().to_msg()
            pub.publish(msg)
            self.times[name].append(time.monotonic())

        self.keep.append(node.create_timer(1.0 / hz, tick))

    def latched(self, node: Node, topic: str, kind: Any, msg: Any) -> None:
        pub = node.create_publisher(kind, topic, LATCHED)
        pub.publish(msg)
        self.types[pub.topic_name] = _type_name(kind)
        self.keep.append(pub)

    def lifecycle_up(self, node: LifecycleNode) -> None:
        """configure, then activate: what Nav2's lifecycle manager does to each of its nodes."""
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        assert node.trigger_activate() == TransitionCallbackReturn.SUCCESS

    def action(self, node: Node, name: str, execute: Callable[[Any], Any] | None = None) -> None:
        server = ActionServer(
            node, Fibonacci, name, execute or self._finish_at_once,
            goal_callback=lambda _g: GoalResponse.ACCEPT, cancel_callback=lambda _g: CancelResponse.ACCEPT,
            callback_group=ReentrantCallbackGroup(),
        )  # fmt: skip
        self.servers.append(server)

    @staticmethod
    def _finish_at_once(goal: Any) -> Any:
        goal.succeed()
        return Fibonacci.Result()

    # -- the waves ---------------------------------------------------------------------------------
    def wave1(self) -> None:
        a, hub = self.args, self.args.hub
        rsp = self.node("robot_state_publisher")
        self.latched(rsp, "/robot_description", String, String(data="<robot name='base'/>" * 50))
        self.periodic(rsp, "/joint_states", JointState, 30.0, _joints, stamp=True)
        lidar = self.node("lidar_driver")
        self.periodic(lidar, "/scan", LaserScan, 10.0, _scan, qos_profile_sensor_data, stamp=True)
        imu = self.node("imu_driver")
        self.periodic(imu, "/imu/data", Imu, 100.0, Imu, qos_profile_sensor_data, stamp=True)
        diag = self.node("diagnostic_aggregator")
        self.periodic(diag, "/diagnostics", DiagnosticArray, 1.0, _diagnostics)
        ms = self.node("map_server", lifecycle=True)
        self.latched(ms, "/map", OccupancyGrid, _grid(384))
        amcl = self.node("amcl", lifecycle=True)
        self.periodic(
            amcl, "/amcl_pose", PoseWithCovarianceStamped, 2.0, PoseWithCovarianceStamped, stamp=True
        )
        self.periodic(amcl, "/particle_cloud", PoseArray, 5.0, _particles, qos_profile_sensor_data)
        planner = self.node("planner_server", lifecycle=True)
        self.periodic(planner, "/global_costmap/costmap", OccupancyGrid, 1.0, lambda: _grid(200))
        self.periodic(planner, "/global_costmap/published_footprint", PolygonStamped, 5.0, _footprint)
        self.action(planner, "compute_path_to_pose")
        controller = self.node("controller_server", lifecycle=True)
        self.periodic(controller, "/local_costmap/costmap", OccupancyGrid, 2.0, lambda: _grid(60))
        self.periodic(controller, "/local_costmap/published_footprint", PolygonStamped, 5.0, _footprint)
        self.periodic(controller, "/local_plan", Path, 10.0, Path)
        self.periodic(controller, "/trajectories", MarkerArray, 5.0, _markers)
        self.follow_path(controller, "", a.drive_topic)
        nav = self.node("bt_navigator", lifecycle=True)
        self.periodic(nav, "/waypoints", MarkerArray, 1.0, _markers)
        self.action(nav, "navigate_to_pose")
        self.navigator = ActionClient(nav, Fibonacci, "follow_path", callback_group=ReentrantCallbackGroup())
        manager = self.node("lifecycle_manager_navigation")
        self.introspected_services(manager)
        for name in ("map_server", "amcl", "planner_server", "controller_server", "bt_navigator"):
            self.lifecycle_up(self.nodes[f"/{name}"])  # type: ignore[arg-type]
        self.hub("sensor_hub", range(0, hub // 2))
        odom = self.node("odom_listener")  # the pose the controller follows: the backend's simulated base
        self.times["/odom"] = []
        odom.create_subscription(Odometry, "/odom", self._on_odom, 10)

    def wave2(self) -> None:
        behaviors = self.node("behavior_server", lifecycle=True)
        for name in ACTIONS["behavior_server"]:
            self.action(behaviors, name)
        follower = self.node("waypoint_follower", lifecycle=True)
        self.action(follower, "follow_waypoints")
        for n in (behaviors, follower):
            self.lifecycle_up(n)  # type: ignore[arg-type]
        self.hub("sensor_hub_2", range(self.args.hub // 2, self.args.hub))
        # a second robot in its own namespace: a base with its own odometry, scan and controller
        base2 = self.node("base_driver", "/robot2")
        self.periodic(base2, "odom", Odometry, 50.0, Odometry, stamp=True)
        self.periodic(base2, "scan", LaserScan, 10.0, _scan, qos_profile_sensor_data, stamp=True)
        controller2 = self.node("controller_server", "/robot2", lifecycle=True)
        self.periodic(controller2, "local_plan", Path, 10.0, Path)
        self.action(controller2, "follow_path")
        self.lifecycle_up(controller2)  # type: ignore[arg-type]

    def hub(self, name: str, indices: range) -> None:
        node = self.node(name)
        for i in indices:
            hz = HUB_RATES[i % len(HUB_RATES)]
            self.periodic(node, f"/hub/sensor_{i:03d}", Float32, hz, lambda: Float32(data=1.0))

    def introspected_services(self, manager: Node) -> None:
        """``is_active`` and ``manage_nodes``, introspected (contents); an "rviz" asks twice a second."""
        clock = manager.get_clock()
        for srv_name in ("is_active", "manage_nodes"):
            srv = manager.create_service(Trigger, f"~/{srv_name}", self._answer)
            srv.configure_introspection(
                clock, qos_profile_services_default, ServiceIntrospectionState.CONTENTS
            )
            self.keep.append(srv)
        rviz = self.node("rviz")
        client = rviz.create_client(Trigger, "/lifecycle_manager_navigation/is_active")
        client.configure_introspection(
            rviz.get_clock(), qos_profile_services_default, ServiceIntrospectionState.CONTENTS
        )
        self.keep.append(client)
        self.calls: list[float] = []

        def ask() -> None:
            if client.service_is_ready():
                client.call_async(Trigger.Request())
                self.calls.append(time.monotonic())

        self.keep.append(rviz.create_timer(0.5, ask))

    @staticmethod
    def _answer(_req: Any, resp: Any) -> Any:
        resp.success, resp.message = True, "active"
        return resp

    # -- the controller behind follow_path ----------------------------------------------------------
    def _on_odom(self, m: Odometry) -> None:
        self.times["/odom"].append(time.monotonic())  # the truth of the backend's /odom, as heard here
        q = m.pose.pose.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        self.pose = (m.pose.pose.position.x, m.pose.pose.position.y, yaw)

    def follow_path(self, node: Node, namespace: str, drive_topic: str) -> None:
        drive = node.create_publisher(Twist, drive_topic, 10)
        said = node.create_publisher(TwistStamped, "/cmd_vel", 10)
        plan_pub = node.create_publisher(Path, "/plan", 10)
        goal_pub = node.create_publisher(PoseStamped, "/goal_pose", 10)
        for topic, kind in (("/cmd_vel", TwistStamped), ("/plan", Path), ("/goal_pose", PoseStamped)):
            self.times[topic], self.types[topic] = [], _type_name(kind)
        feedback_topic = "/follow_path/_action/feedback"
        self.times[feedback_topic] = []

        def execute(goal: Any) -> Any:
            record = self.goals[-1]
            x_goal, y_goal = record["goal"]
            pose_msg = PoseStamped()
            pose_msg.header.frame_id = "odom"
            pose_msg.pose.position.x, pose_msg.pose.position.y, pose_msg.pose.orientation.w = (
                x_goal,
                y_goal,
                1.0,
            )
            goal_pub.publish(pose_msg)
            self.times["/goal_pose"].append(time.monotonic())
            x0, y0, _ = self.pose
            path = Path()
            path.header.frame_id = "odom"
            for k in range(11):
                p = PoseStamped()
                p.pose.position.x, p.pose.position.y = (
                    x0 + (x_goal - x0) * k / 10,
                    y0 + (y_goal - y0) * k / 10,
                )
                p.pose.orientation.w = 1.0
                path.poses.append(p)
            record["plan"] = [(p.pose.position.x, p.pose.position.y) for p in path.poses]
            feedback = Fibonacci.Feedback()
            n = 0
            while True:
                if self.closing.is_set():
                    goal.abort()
                    record["ended"], record["at"] = "aborted", time.monotonic()
                    return Fibonacci.Result()
                if goal.is_cancel_requested:
                    drive.publish(Twist())
                    goal.canceled()
                    record["ended"], record["at"] = "canceled", time.monotonic()
                    return Fibonacci.Result()
                x, y, yaw = self.pose
                dist = math.hypot(x_goal - x, y_goal - y)
                if dist < 0.05:
                    drive.publish(Twist())
                    goal.succeed()
                    record["ended"], record["at"] = "succeeded", time.monotonic()
                    return Fibonacci.Result()
                heading = math.atan2(y_goal - y, x_goal - x) - yaw
                heading = math.atan2(math.sin(heading), math.cos(heading))
                cmd = Twist()
                cmd.linear.x = min(0.2, dist) * max(0.0, math.cos(heading))
                cmd.angular.z = max(-1.0, min(1.0, 1.5 * heading))
                drive.publish(cmd)
                stamped = TwistStamped()
                stamped.header.stamp = node.get_clock().now().to_msg()
                stamped.twist = cmd
                said.publish(stamped)
                self.times["/cmd_vel"].append(time.monotonic())
                if n % 10 == 0:
                    path.header.stamp = stamped.header.stamp
                    plan_pub.publish(path)
                    self.times["/plan"].append(time.monotonic())
                if n % 2 == 0:
                    feedback.sequence = [n]
                    goal.publish_feedback(feedback)
                    self.times[feedback_topic].append(time.monotonic())
                n += 1
                time.sleep(0.05)  # a 20 Hz controller, as Nav2's default

        self.action(node, "follow_path", execute)

    def send_goal(self, x: float, y: float) -> None:
        with self.lock:
            self.goals.append({"goal": (x, y), "ended": None, "sent": time.monotonic()})
        goal = Fibonacci.Goal()
        goal.order = 1
        self.navigator.send_goal_async(goal)

    def dump(self) -> dict[str, Any]:
        nodes = self.nodes.values()
        services: dict[str, list[str]] = {}
        actions: dict[str, list[str]] = {}
        probe = next(iter(nodes))
        for name, types in probe.get_service_names_and_types():
            services[name] = types
        for name in {s.split("/_action/")[0] for s in services if "/_action/" in s}:
            actions[name] = ["test_msgs/action/Fibonacci"]
        return {
            "times": {k: list(v) for k, v in self.times.items()},
            "types": self.types,
            "goals": self.goals,
            "calls": list(getattr(self, "calls", [])),
            "services": services,
            "actions": actions,
        }


def _type_name(kind: Any) -> str:
    module = kind.__module__.split(".")
    return f"{module[0]}/{module[1].lstrip('_')}/{kind.__name__}"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--hub", type=int, default=100, help="further topics of a sensor hub (default 100)")
    p.add_argument("--wave2-after", type=float, default=3.0, help="seconds before the second wave")
    p.add_argument("--drive-topic", default="/cmd_vel_measured", help="what the simulated base takes")
    args = p.parse_args(argv)
    rclpy.init()
    graph = Graph(args)
    graph.wave1()
    threading.Thread(target=graph.executor.spin, daemon=True).start()
    print("ready 1", flush=True)

    def later() -> None:
        time.sleep(args.wave2_after)
        graph.wave2()
        print("ready 2", flush=True)

    threading.Thread(target=later, daemon=True).start()
    for line in sys.stdin:
        cmd, *rest = line.split()
        if cmd == "goal":
            graph.send_goal(float(rest[0]), float(rest[1]))
        elif cmd == "dump":
            print(json.dumps(graph.dump()), flush=True)
        elif cmd == "quit":
            break
    graph.closing.set()
    deadline = time.monotonic() + 2.0
    while any(g["ended"] is None for g in graph.goals) and time.monotonic() < deadline:
        time.sleep(0.05)  # the running goal sees ``closing`` within one of its 20 Hz ticks
    graph.executor.shutdown(timeout_sec=2)
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
