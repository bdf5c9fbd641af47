"""The seed's autonomous behaviour node, on the robot (``arbiter-backend --autonomy``).

One of the console's controllers (``arbiter_core.controllers``, the same code) follows a named mission
on the robot's own odometry, in the backend's process: no link inside the control loop. It publishes
what a robot-side controller leaves on the graph, which the console's observe mode grades
(docs/analytics.md, "Grade any controller"): ``plan`` (``nav_msgs/Path``: where the run started, then every
waypoint), ``goal_pose`` (``geometry_msgs/PoseStamped``: the last waypoint), and each command as a
stamped envelope on ``stamped_cmd_vel`` (the seed's section 6.1: commands that are time-stamped and
measured by the latency tracker, which forwards them to ``cmd_vel_measured``).

As the console's control loop: a command every ``CONTROL_PERIOD`` odometry messages (50 Hz odometry:
10 Hz, compare's rate), the controller capped at the run's speed and turn (``clamp_twist``), the mission
relative to where the robot stands when it starts, a waypoint passed within 0.15 m; when the last is
reached, one zero command and the run is ``completed``. A stop (``DELETE /api/autonomy``) sends one
zero and the run is ``aborted``; the tracker's deadman stops the robot if the process dies.

Pure logic (``Autonomy``) and the service the API drives; the transport wires it
(``server.Backend`` on the embedded bus, ``ros.autonomy.AutonomyNode`` on DDS).
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, replace
from typing import Any

from arbiter_core.controllers import CONTROLLERS, MISSIONS, make_controller
from arbiter_core.kinematics import (
    DEFAULT_LIMITS,
    Limits,
    Pose,
    clamp_twist,
    distance_error,
    odometry_jumped,
    pose_of_odometry,
    yaw_to_quaternion,
)
from arbiter_core.mission import Mission, Phase

CONTROL_PERIOD = 5  # odometry messages per command (the simulator's 50 Hz -> 10 Hz)
IDLE = "idle"  # before the first run; then the run's phase (arbiter_core.mission.Phase)
RUNNING, COMPLETED, ABORTED = Phase.RUNNING.value, Phase.COMPLETED.value, Phase.ABORTED.value
TYPE_PATH = "nav_msgs/msg/Path"
TYPE_POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
PLAN, GOAL = "plan", "goal_pose"


def _wall_ms() -> float:
    return time.time_ns() / 1e6


class AutonomyError(ValueError):
    """A request the autonomy cannot take, in one line (the API's 400)."""


@dataclass(frozen=True)
class Request:
    algorithm: str
    mission: str
    speed: float = 0.5  # the console's default caps
    turn: float = 1.0

    @classmethod
    def from_json(cls, raw: Any) -> Request:
        """ValueError naming the field that is wrong."""
        if not isinstance(raw, dict):
            raise AutonomyError('the body must be a JSON object: {"algorithm": ..., "mission": ...}')
        algorithm, mission = raw.get("algorithm"), raw.get("mission", "square")
        if algorithm not in CONTROLLERS:
            raise AutonomyError(f"algorithm must be one of {', '.join(CONTROLLERS)}")
        if mission not in MISSIONS:
            raise AutonomyError(f"mission must be one of {', '.join(MISSIONS)}")
        caps = {}
        for name, top in (("speed", DEFAULT_LIMITS.max_linear), ("turn", DEFAULT_LIMITS.max_angular)):
            value = raw.get(name, getattr(cls, name))
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
                raise AutonomyError(f"{name} must be a finite number")
            if not 0 < value <= top:
                raise AutonomyError(f"{name} must be in (0, {top}]")
            caps[name] = float(value)
        return cls(algorithm, mission, **caps)


def _pose_stamped(x: float, y: float, yaw: float, stamp: dict[str, int], frame: str) -> dict[str, Any]:
    return {
        "header": {"stamp": stamp, "frame_id": frame},
        "pose": {"position": {"x": x, "y": y, "z": 0.0}, "orientation": yaw_to_quaternion(yaw)},
    }


class Autonomy:
    """A controller following a mission on odometry (module doc)."""

    def __init__(self, frame_id: str = "odom") -> None:
        self.frame_id = frame_id
        self.request: Request | None = None
        self.mission: Mission | None = None  # the run in progress, or the last one
        self._controller: Any = None
        self._limits: Limits = DEFAULT_LIMITS
        self._count = 0
        self.commands = 0
        self.final_error_m: float | None = None

    @property
    def outcome(self) -> str:
        return IDLE if self.mission is None else self.mission.phase.value

    @property
    def running(self) -> bool:
        return self.mission is not None and self.mission.running

    def start(
        self, request: Request, pose: Pose, stamp: dict[str, int], now_ms: float = 0.0
    ) -> list[tuple[str, dict[str, Any]]]:
        """Start ``request`` from ``pose``; returns the messages to publish first (plan, goal)."""
        mission = Mission.named(request.mission, request.algorithm, pose, now_ms)
        self.request, self.mission = request, mission
        self._limits = replace(DEFAULT_LIMITS, max_linear=request.speed, max_angular=request.turn)
        self._controller = make_controller(request.algorithm, self._limits)
        self._count, self.commands, self.final_error_m = 0, 0, None
        points = [mission.start, *mission.waypoints]
        poses = []
        for i, (x, y) in enumerate(points):
            nx, ny = points[min(i + 1, len(points) - 1)]
            yaw = math.atan2(ny - y, nx - x) if (nx, ny) != (x, y) else pose.theta
            poses.append(_pose_stamped(x, y, yaw, stamp, self.frame_id))
        plan = {"header": {"stamp": stamp, "frame_id": self.frame_id}, "poses": poses}
        goal = poses[-1]
        return [(PLAN, plan), (GOAL, goal)]

    def on_odometry(self, pose: Pose, now_ms: float = 0.0) -> tuple[float, float] | None:
        """Every odometry message; the command to send, on every ``CONTROL_PERIOD``-th while running."""
        mission = self.mission
        if mission is None or not mission.running:
            return None
        self._count += 1
        if (self._count - 1) % CONTROL_PERIOD:
            return None
        mission = self.mission = mission.advanced(pose)
        if mission.done:
            self.mission = mission.ended(Phase.COMPLETED, now_ms)
            self.final_error_m = distance_error(pose, mission.waypoints[-1])
            return (0.0, 0.0)
        want_v, want_w = self._controller.command(pose, mission)
        v, w = clamp_twist(want_v, want_w, self._limits)
        self.commands += 1
        return v, w

    def stop(self, now_ms: float = 0.0) -> tuple[float, float] | None:
        """Abort a run in progress: the zero command to send (None when nothing runs)."""
        if self.mission is None or not self.mission.running:
            return None
        self.mission = self.mission.ended(Phase.ABORTED, now_ms)
        return (0.0, 0.0)

    def status(self) -> dict[str, Any]:
        r = self.request
        m = self.mission
        return {
            "state": self.outcome,
            "algorithm": None if r is None else r.algorithm,
            "mission": None if r is None else r.mission,
            "speed": None if r is None else r.speed,
            "turn": None if r is None else r.turn,
            "waypoint": None if m is None else m.reached,
            "waypoints": None if m is None else m.total,
            "commands": self.commands,
            "final_error_m": None if self.final_error_m is None else round(self.final_error_m, 4),
        }


class AutonomyService:
    """What ``/api/autonomy`` drives: an :class:`Autonomy` wired to a transport by three callables
    (publish a message on ``plan``/``goal_pose``, send a command, the latest odometry pose)."""

    def __init__(
        self,
        publish: Any,  # (topic key PLAN or GOAL, message) -> None
        send: Any,  # (v, w) -> None: a stamped command onto the tracker's path
        stamp: Any,  # () -> {"sec", "nanosec"}
        frame_id: str = "odom",
    ) -> None:
        self.autonomy = Autonomy(frame_id)
        self._publish, self._send, self._stamp = publish, send, stamp
        self.pose: Pose | None = None
        self._pose_at: float | None = None  # monotonic s of the last pose
        # ROS mode: odometry on the executor's thread, requests on the API's loop
        self._lock = threading.Lock()

    def on_odometry(self, odom: dict[str, Any]) -> None:
        """An odometry message in rosbridge JSON form (the embedded bus's)."""
        try:
            pose = pose_of_odometry(odom)
        except (KeyError, TypeError, ValueError):
            return  # not odometry with a pose: nothing to drive by
        self.on_pose(pose)

    def on_pose(self, pose: Pose) -> None:
        """The robot's pose from its odometry; the command, when one is due, is sent from here. A pose
        that jumped further than the robot can drive (its odometry reset or restarted) ends a run in
        progress as aborted, with a zero: its waypoints are in a frame that no longer exists."""
        now = time.monotonic()
        with self._lock:
            before, at = self.pose, self._pose_at
            self.pose, self._pose_at = pose, now
            if before is not None and at is not None and odometry_jumped(before, pose, now - at):
                if (zero := self.autonomy.stop(_wall_ms())) is not None:
                    self._send(*zero)
                return
            cmd = self.autonomy.on_odometry(pose, _wall_ms())
            if cmd is not None:
                self._send(*cmd)

    def start(self, raw: Any) -> dict[str, Any]:
        """AutonomyError (400) for a bad request, RuntimeError (409) with no odometry yet."""
        request = Request.from_json(raw)
        with self._lock:
            if self.pose is None:
                raise RuntimeError("no odometry yet: the robot's pose is unknown")
            if (zero := self.autonomy.stop(_wall_ms())) is not None:
                self._send(*zero)  # the run in progress ends first
            for key, msg in self.autonomy.start(request, self.pose, self._stamp(), _wall_ms()):
                self._publish(key, msg)
            return self.autonomy.status()

    def stop(self) -> dict[str, Any]:
        """Abort the run in progress (one zero); ``stopped`` in the answer says whether one was."""
        with self._lock:
            zero = self.autonomy.stop(_wall_ms())
            if zero is not None:
                self._send(*zero)
            return {**self.autonomy.status(), "stopped": zero is not None}

    def status(self) -> dict[str, Any]:
        with self._lock:
            return self.autonomy.status()
