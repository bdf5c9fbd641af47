"""The tracker and the simulator as ordinary rclpy nodes, around the same classes the embedded transport uses.

``latency_tracker``: ``stamped_cmd_vel`` (std_msgs/String) in; ``latency_report``
(String) and ``cmd_vel_measured`` (Twist, or TwistStamped stamped with the receive
time) out; a watchdog timer sends one zero when commands stop. That timer is a callback of the rclpy
executor: while the executor is down (restarting after a failure, ``executor_changed``) a zero goes
out at once and every command that reaches the tracker from the rosbridge relay's event loop is
forwarded as a zero, until the executor runs again. ``arbiter_simulator``:
``cmd_vel_measured`` in, ``odom`` (nav_msgs/Odometry) out at ``rate_hz``. Every
subscription is reliable and VOLATILE, so a node that starts late never receives
old commands. Flags become parameter defaults; ``--ros-args -p name:=value``
overrides them.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from typing import Any

from rclpy.context import Context
from rclpy.node import Node

from arbiter_core import simulator, topics
from arbiter_core.kinematics import Limits

from .. import tracker
from ..config import BackendConfig
from ..supervise import WorkerRecord
from .bus import default_qos
from .convert import message_class, to_json, to_ros
from .local import HandledLocally

log = logging.getLogger(__name__)


class ParameterError(ValueError):
    """A ROS parameter with a value the node cannot use."""


def _positive(name: str, value: float) -> float:
    if not value > 0:
        raise ParameterError(f"parameter {name} must be positive, got {value}")
    return float(value)


def _measured(value: str) -> str:
    if value not in topics.MEASURED_TYPES:
        raise ParameterError(f"parameter measured_type must be one of {', '.join(topics.MEASURED_TYPES)}")
    return value


def _limits_params(node: Node, config: BackendConfig) -> tuple[Limits, float, str]:
    max_linear: float = node.declare_parameter("max_linear", float(config.limits.max_linear)).value
    max_angular: float = node.declare_parameter("max_angular", float(config.limits.max_angular)).value
    lin_acc: float = node.declare_parameter("max_linear_accel", float(config.limits.max_linear_accel)).value
    ang_acc: float = node.declare_parameter("max_angular_accel", float(config.limits.max_angular_accel)).value
    cmd_timeout: float = node.declare_parameter("cmd_timeout", float(config.cmd_timeout)).value
    measured_type: str = node.declare_parameter("measured_type", config.measured_type).value
    limits = dataclasses.replace(
        config.limits,
        max_linear=_positive("max_linear", max_linear),
        max_angular=_positive("max_angular", max_angular),
        max_linear_accel=_positive("max_linear_accel", lin_acc),
        max_angular_accel=_positive("max_angular_accel", ang_acc),
    )
    return limits, _positive("cmd_timeout", cmd_timeout), _measured(measured_type)


class TrackerNode(Node):
    def __init__(self, config: BackendConfig, context: Context) -> None:
        super().__init__(tracker.NODE_NAME, namespace=config.namespace, context=context)
        limits, cmd_timeout, measured_type = _limits_params(self, config)
        deploy_mode: str = self.declare_parameter("deploy_mode", config.deploy_mode).value
        max_records = int(self.declare_parameter("max_records", config.max_records).value)
        if max_records < 1:
            raise ParameterError(f"parameter max_records must be at least 1, got {max_records}")
        api_port = int(self.declare_parameter("api_port", config.api_port).value)
        if not 0 <= api_port <= 65535:
            raise ParameterError(f"parameter api_port must be 0..65535, got {api_port}")
        host: str = self.declare_parameter("host", config.host).value
        max_age = float(self.declare_parameter("max_command_age_ms", float(config.max_command_age_ms)).value)
        if not max_age >= 0:
            raise ParameterError(f"parameter max_command_age_ms must be 0 (off) or positive, got {max_age}")
        self.config = dataclasses.replace(
            config,
            limits=limits,
            cmd_timeout=cmd_timeout,
            measured_type=measured_type,
            deploy_mode=str(deploy_mode),
            max_records=max_records,
            api_port=api_port,
            host=str(host),
            max_command_age_ms=max_age,
        )
        self.tracker = self.config.make_tracker()
        qos = default_qos()
        self._string = message_class(topics.TYPE_STRING)
        self._measured_cls = message_class(topics.MEASURED_TYPES[measured_type])
        self.report_pub = self.create_publisher(self._string, topics.REPORT, qos)
        self.measured_pub = self.create_publisher(self._measured_cls, topics.MEASURED, qos)
        self.stamped_sub = self.create_subscription(self._string, topics.STAMPED, self._on_stamped, qos)
        self.create_timer(min(0.05, cmd_timeout / 4), self._watchdog)
        # set by the backend when the rosbridge relay runs in this process (RosBus.deliver_local)
        self.local_report: Callable[[str, str], None] | None = None
        self._local = HandledLocally()  # commands handled in-process whose DDS copy is still to come
        self.halted: str | None = None  # why commands are forwarded as zeros (the executor is down)

    def _forward(self, v: float, w: float, stamp_ns: int) -> None:
        msg = topics.measured_message(v, w, self.config.measured_type, stamp_ns)
        self.measured_pub.publish(to_ros(self._measured_cls, msg))

    def publish_zero(self) -> None:
        """One zero twist on the command output now, as the watchdog sends (any thread: rclpy's publish is
        thread-safe)."""
        self._forward(0.0, 0.0, self.get_clock().now().nanoseconds)

    def executor_changed(self, w: WorkerRecord) -> None:
        """The supervisor's listener of the executor that spins this node (its watchdog): when it goes
        down, one zero now and commands forwarded as zeros (no watchdog would end them); when it runs
        again, commands drive again."""
        if w.state in ("restarting", "failed"):
            if self.halted is None:
                log.error("latency_tracker: the executor is down (%s): zero sent, commands held", w.error)
            self.halted = f"the rclpy executor is {w.state}: {w.error}"
            self.publish_zero()
        elif w.state == "running" and self.halted is not None:
            self.halted = None
            log.warning("latency_tracker: the executor runs again: commands drive again")

    def on_local_command(self, text: str) -> None:
        """A command the rosbridge relay of this process received: handled now, on the caller's thread,
        instead of after a DDS round through the executor. The relay still publishes it on DDS for
        every other subscriber; its DDS copy reaching this node is then skipped (counted by text, so a
        client that sends the same text twice is handled twice)."""
        self._local.note(text)
        self._handle(text)

    def _on_stamped(self, msg: Any) -> None:
        if self._local.take(msg.data):
            return  # handled already, in-process
        self._handle(msg.data)

    def _handle(self, text: str) -> None:
        recv_ns = self.get_clock().now().nanoseconds
        try:
            accepted = self.tracker.on_stamped(text, recv_ns)
            if accepted is None:
                return
            if self.local_report is not None:  # first: registered before the DDS copy can arrive
                self.local_report(self.report_pub.topic_name, accepted.text)
            self.report_pub.publish(self._string(data=accepted.text))
            if accepted.forward is not None:
                # no watchdog runs while the executor is down: nothing may drive then
                self._forward(*(accepted.forward if self.halted is None else (0.0, 0.0)), recv_ns)
        except Exception:  # a callback that raises would stop the executor, and with it the robot's stop
            log.exception("latency_tracker: command handling failed")

    def _watchdog(self) -> None:
        try:
            if self.tracker.watchdog_due():
                log.info("no command for %.2fs: publishing zero twist", self.config.cmd_timeout)
                self._forward(0.0, 0.0, self.get_clock().now().nanoseconds)
        except Exception:
            log.exception("latency_tracker: watchdog failed")


class SimulatorNode(Node):
    def __init__(self, config: BackendConfig, context: Context) -> None:
        super().__init__(simulator.NODE_NAME, namespace=config.namespace, context=context)
        limits, cmd_timeout, measured_type = _limits_params(self, config)
        rate = _positive("rate_hz", self.declare_parameter("rate_hz", simulator.RATE_HZ).value)
        self.sim = simulator.DiffDriveSimulator(limits, cmd_timeout=cmd_timeout)
        qos = default_qos()
        self._odom_cls = message_class(topics.TYPE_ODOM)
        self.odom_pub = self.create_publisher(self._odom_cls, topics.ODOM, qos)
        measured_cls = message_class(topics.MEASURED_TYPES[measured_type])
        self.create_subscription(measured_cls, topics.MEASURED, self._on_twist, qos)
        self.create_timer(1.0 / rate, self._tick)

    def _on_twist(self, msg: Any) -> None:
        try:
            self.sim.on_twist(to_json(msg), time.monotonic())
        except Exception:
            log.exception("arbiter_simulator: bad twist")

    def _tick(self) -> None:
        try:
            odom = self.sim.tick(time.monotonic(), self.get_clock().now().nanoseconds)
            self.odom_pub.publish(to_ros(self._odom_cls, odom))
        except Exception:
            log.exception("arbiter_simulator: tick failed")
