"""The robot-side autonomy as an rclpy node (``arbiter_autonomy``): ``arbiter-backend --transport ros
--autonomy``. Odometry in, ``plan`` and ``goal_pose`` (transient local, as a latched plan) and stamped
commands on ``stamped_cmd_vel`` out, all relative to the namespace; the logic is ``autonomy.py``'s."""

from __future__ import annotations

import itertools
import logging
from typing import Any

from rclpy.context import Context
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from arbiter_core import envelope, topics
from arbiter_core.kinematics import Pose, quaternion_to_yaw

from .. import autonomy as A
from ..config import BackendConfig
from .bus import default_qos
from .convert import message_class, to_ros

log = logging.getLogger(__name__)
NODE_NAME = "arbiter_autonomy"


class AutonomyNode(Node):
    def __init__(self, config: BackendConfig, context: Context) -> None:
        super().__init__(NODE_NAME, namespace=config.namespace, context=context)
        qos = default_qos()
        latched = QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
        )
        self._string = message_class(topics.TYPE_STRING)
        classes = {A.PLAN: message_class(A.TYPE_PATH), A.GOAL: message_class(A.TYPE_POSE_STAMPED)}
        self._classes = classes
        self._pubs = {key: self.create_publisher(cls, key, latched) for key, cls in classes.items()}
        self._cmd = self.create_publisher(self._string, topics.STAMPED, qos)
        self._seq = itertools.count(1)
        self.service = A.AutonomyService(self._publish, self._send, self._stamp)
        self.create_subscription(message_class(topics.TYPE_ODOM), topics.ODOM, self._on_odom, qos)

    def _publish(self, key: str, msg: dict[str, Any]) -> None:
        self._pubs[key].publish(to_ros(self._classes[key], msg))

    def _send(self, v: float, w: float) -> None:
        self._cmd.publish(self._string(data=envelope.build(v, w, seq=next(self._seq))))

    def _stamp(self) -> dict[str, int]:
        return topics.stamp(self.get_clock().now().nanoseconds)

    def _on_odom(self, msg: Any) -> None:
        # the pose read from the message as it is (50 Hz): not the whole Odometry made JSON first
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        try:
            self.service.on_pose(Pose(p.x, p.y, quaternion_to_yaw({"x": q.x, "y": q.y, "z": q.z, "w": q.w})))
        except Exception:
            log.exception("arbiter_autonomy: odometry not taken")
