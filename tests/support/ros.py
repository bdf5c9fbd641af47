"""An rclpy peer for the ROS-mode tests: its own context and domain, spun in a thread.

The tests run on a random ROS domain with discovery limited to this host, so
concurrent runs on one machine never see each other's topics; each test module takes the next domain
(``use_test_domain``), so a module never sees what an earlier one left on the graph (a participant that
went away is seen for a while after, until discovery drops it).
"""

import contextlib
import itertools
import os
import random
import threading
import time

import pytest

try:
    import rclpy

    # re-exported for the tests, so that a missing ROS skips (or fails) here, in one place
    from geometry_msgs.msg import PoseStamped, Twist, TwistStamped  # noqa: F401
    from nav_msgs.msg import Odometry  # noqa: F401
    from rclpy.context import Context
    from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor, SingleThreadedExecutor
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: F401
    from std_msgs.msg import String  # noqa: F401
except ImportError as exc:  # pragma: no cover - depends on the install
    if os.environ.get("ARBITER_REQUIRE_ROS"):
        raise RuntimeError(f"ARBITER_REQUIRE_ROS is set but rclpy is not importable: {exc}") from exc
    pytest.skip(
        f"rclpy not importable ({exc}): pip install -e '.[ros]' or source a ROS 2 install",
        allow_module_level=True,
    )

DOMAIN = random.Random(os.getpid()).randint(1, 100)  # this run's first; see ``domain``
_modules = itertools.count()


def domain() -> int:
    """The domain the current module runs on (set by ``use_test_domain``)."""
    return int(os.environ.get("ROS_DOMAIN_ID", DOMAIN))


def use_test_domain():
    """Generator for a module-scoped autouse fixture: the module's own domain (this run's next one, in
    1..100), discovery on this host only."""
    saved = {k: os.environ.get(k) for k in ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE")}
    current = (DOMAIN - 1 + next(_modules)) % 100 + 1
    os.environ["ROS_DOMAIN_ID"] = str(current)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    yield current
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


class Peer:
    def __init__(self, name: str = "arbiter_test_peer", threads: int = 1) -> None:
        """``threads`` > 1: callbacks that block (an action server's) do not hold the others up."""
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain())
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = (
            MultiThreadedExecutor(num_threads=threads, context=self.context)
            if threads > 1
            else SingleThreadedExecutor(context=self.context)
        )
        self.executor.add_node(self.node)
        self.subscriptions: dict = {}
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        with contextlib.suppress(ExternalShutdownException):
            self.executor.spin()

    def collect(self, msg_type, topic: str, convert=lambda m: m) -> list:
        got: list = []
        self.subscriptions[topic] = self.node.create_subscription(
            msg_type, topic, lambda m: got.append(convert(m)), 10
        )
        return got

    def matched(self, topic: str) -> int:
        """Publishers matched to the subscription ``collect`` made on ``topic`` (DDS discovery done)."""
        return self.subscriptions[topic].get_publisher_count()

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=2)
        self.thread.join(2)
        self.node.destroy_node()
        self.context.try_shutdown()


def serve_flag_and_fibonacci(node, service: str, action: str):
    """What the client tests call on the peer: a ``std_srvs/SetBool`` ``service`` that says what it set, and
    a ``test_msgs/action/Fibonacci`` ``action`` that sends each partial sequence as feedback. Returns the
    action server (the caller keeps it alive)."""
    from rclpy.action import ActionServer
    from std_srvs.srv import SetBool
    from test_msgs.action import Fibonacci

    def set_flag(request, response):
        response.success, response.message = request.data, f"flag set to {request.data}"
        return response

    node.create_service(SetBool, service, set_flag)

    def fibonacci(goal_handle):
        seq = [0, 1]
        for i in range(1, goal_handle.request.order):
            seq.append(seq[i] + seq[i - 1])
            goal_handle.publish_feedback(Fibonacci.Feedback(sequence=seq))
        goal_handle.succeed()
        return Fibonacci.Result(sequence=seq)

    return ActionServer(node, Fibonacci, action, fibonacci)


class Navigator:
    """``action`` on ``peer`` as Nav2's navigator serves it (the Fibonacci type stands in for
    NavigateToPose: a cancel is the same service for every action): while a goal runs, Twist 0.3 m/s on
    ``cmd_topic`` at 20 Hz, for up to a minute; a cancel request is accepted and ends the goal canceled.
    What it saw is kept: ``cancels`` (the monotonic time of each cancel request) and ``ended`` (each goal's
    end, "canceled" or "aborted"). The peer needs ``threads`` > 1 (``execute`` blocks while it drives)."""

    def __init__(self, peer: Peer, cmd_topic: str, action: str = "/navigate_to_pose") -> None:
        from geometry_msgs.msg import Twist
        from rclpy.action import ActionServer, CancelResponse, GoalResponse
        from test_msgs.action import Fibonacci

        self.action_type = Fibonacci
        self.cancels: list[float] = []
        self.ended: list[str] = []
        self.executing = 0  # goals executing now
        self._drive = peer.node.create_publisher(Twist, cmd_topic, 10)
        self._cmd = Twist()
        self._cmd.linear.x = 0.3

        def cancel(_goal) -> CancelResponse:
            self.cancels.append(time.monotonic())
            return CancelResponse.ACCEPT

        self.server = ActionServer(
            peer.node, Fibonacci, action, execute_callback=self._execute,
            goal_callback=lambda _g: GoalResponse.ACCEPT, cancel_callback=cancel,
        )  # fmt: skip

    def _execute(self, goal):
        self.executing += 1
        try:
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                if goal.is_cancel_requested:
                    goal.canceled()
                    self.ended.append("canceled")
                    return self.action_type.Result()
                self._drive.publish(self._cmd)
                time.sleep(0.05)
            goal.abort()
            self.ended.append("aborted")
            return self.action_type.Result()
        finally:
            self.executing -= 1

    def destroy(self) -> None:
        self.server.destroy()
