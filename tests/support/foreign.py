"""A foreign controller behind a ROS action, as Nav2's navigator is to the console: a roslibpy node
that drives the robot by publishing Twist on a command topic while its goal is active, and provides its
action's cancel service (``<action>/_action/cancel_goal``, ``action_msgs/srv/CancelGoal``): a cancel of
all goals (a zero goal id and stamp) ends the goal, and its commands stop. ``cancellable=False``: the
same driver with no action server at all (a bare teleop script, a node that ignores cancels)."""

import threading

import roslibpy

from arbiter_core.topics import twist

CANCEL_TYPE = "action_msgs/srv/CancelGoal"


class FakeNav2:
    def __init__(
        self, port: int, cmd_topic: str, action: str = "/navigate_to_pose", cancellable: bool = True
    ) -> None:
        self.ros = roslibpy.Ros("127.0.0.1", port)
        self.ros.run(timeout=10)
        self.action = action
        self._active = threading.Event()
        self._closed = threading.Event()
        self.cancels: list[dict] = []  # the cancel requests received, as sent
        self.v = 0.3
        self._cmd = roslibpy.Topic(self.ros, cmd_topic, "geometry_msgs/Twist")
        self._cmd.advertise()
        self._service = None
        if cancellable:
            self._service = roslibpy.Service(self.ros, f"{action}/_action/cancel_goal", CANCEL_TYPE)
            self._service.advertise(self._cancel)
        self._thread = threading.Thread(target=self._drive, name="fake-nav2", daemon=True)
        self._thread.start()

    @property
    def active(self) -> bool:
        return self._active.is_set()

    def start_goal(self, v: float = 0.3) -> None:
        """A goal arrives: drive at ``v`` until it is cancelled."""
        self.v = v
        self._active.set()

    def _cancel(self, request: dict, response: dict) -> bool:
        self.cancels.append(dict(request))
        info = request.get("goal_info", {})
        everything = info.get("goal_id", {}).get("uuid") == [0] * 16 and info.get("stamp", {}) in (
            {"sec": 0, "nanosec": 0},
            {"sec": 0, "nsec": 0},
        )
        canceling = []
        if everything and self._active.is_set():
            self._active.clear()
            canceling = [{"goal_id": {"uuid": [7] * 16}, "stamp": {"sec": 1, "nanosec": 0}}]
        response["return_code"] = 0 if canceling else 1
        response["goals_canceling"] = canceling
        return True

    def _drive(self) -> None:
        """20 Hz, as a controller server publishes: the goal's command while it is active."""
        while not self._closed.wait(0.05):
            if self._active.is_set():
                self._cmd.publish(roslibpy.Message(twist(self.v, 0.0)))

    def close(self) -> None:
        self._active.clear()
        self._closed.set()
        self._thread.join(2)
        self.ros.close()
