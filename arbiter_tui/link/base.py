"""What every link shares: its states, the telemetry it writes, and the surface the control loop uses.

A link exposes ``state``, ``send(v, w)``, ``telemetry`` (latest pose and latency,
thread-safe) and ``close()``. Link callbacks may run on another thread (roslibpy's
Twisted reactor); they only write :class:`Telemetry` under its lock, and the UI
reads it at its own pace.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import Any, Protocol, runtime_checkable

from arbiter_core.kinematics import Pose, odometry_jumped, pose_of_odometry
from arbiter_core.record import LatencyRecord, RecordError

from ..latency.clocksync import LatencyMeter


class LinkState(str, Enum):
    """Where a link is (the status line shows its value)."""

    STARTING = "STARTING"  # the console is up; its link (and the embedded backend) are being started
    CONNECTING = "CONNECTING"
    CONNECTED = "CONNECTED"
    RECONNECTING = "RECONNECTING"
    DISCONNECTED = "DISCONNECTED"
    SIMULATED = "SIMULATED"  # client-side simulation: no network
    CLOSED = "CLOSED"  # closed on purpose (the console is leaving)

    def __str__(self) -> str:
        return self.value


STARTING, CONNECTING, CONNECTED = LinkState.STARTING, LinkState.CONNECTING, LinkState.CONNECTED
RECONNECTING, DISCONNECTED, SIMULATED = LinkState.RECONNECTING, LinkState.DISCONNECTED, LinkState.SIMULATED
CLOSED = LinkState.CLOSED
ODOM_SILENCE_S = 2.0  # connected this long without odometry: said on screen
ODOM_STALE_S = 0.5  # odometry older than this (the link up) is not sampled: the record has a gap instead


@dataclass
class Telemetry:
    """Latest robot state as seen by the console: written by the link's callbacks (any thread) under
    ``lock``; commands sent, RTT, offset and loss are the meter's."""

    lock: threading.Lock = field(default_factory=threading.Lock, repr=False)
    pose: Pose = field(default_factory=Pose)
    v: float = 0.0
    w: float = 0.0
    odom_count: int = 0
    latency_ms: float | None = None
    reports: int = 0
    odom_at: float | None = None  # monotonic time of the last odometry message
    connected_at: float | None = None  # monotonic time the link last came up
    meter: LatencyMeter = field(default_factory=LatencyMeter)
    # The odometry's life (arbiter_core.mission): bumped when the link is lost or the pose jumps further
    # than the robot can drive (a backend restarted, an odometry reset). Missions, the record's path and
    # what ``g`` resumes never cross from one life to the next.
    life: int = 0
    life_reason: str | None = None  # why the current life began

    def new_life(self, why: str) -> None:
        """The odometry starts a new life (the link was lost: its next pose may be from a restarted
        robot)."""
        with self.lock:
            self._new_life(why)

    def _new_life(self, why: str) -> None:
        self.life += 1
        self.life_reason = why

    def set_odom(self, msg: dict[str, Any]) -> None:
        try:
            pose = pose_of_odometry(msg)
            v = float(msg["twist"]["twist"]["linear"]["x"])
            w = float(msg["twist"]["twist"]["angular"]["z"])
        except (KeyError, TypeError, ValueError):
            return
        now = time.monotonic()
        with self.lock:
            if self.odom_at is not None and odometry_jumped(self.pose, pose, now - self.odom_at):
                jump = math.hypot(pose.x - self.pose.x, pose.y - self.pose.y)
                self._new_life(f"the odometry jumped {jump:.2f} m in {now - self.odom_at:.2f} s")
            self.pose, self.v, self.w = pose, v, w
            self.odom_count += 1
            self.odom_at = now

    def odometry_missing(self, now: float, after_s: float = ODOM_SILENCE_S) -> bool:
        """Connected for ``after_s`` and no odometry in that long (never, or it stopped)."""
        with self.lock:
            if self.connected_at is None:
                return False
            last = self.connected_at if self.odom_at is None else max(self.odom_at, self.connected_at)
            return now - last >= after_s

    def odometry_live(self, now: float, stale_s: float = ODOM_STALE_S) -> bool:
        """Odometry fresh enough to record: within ``stale_s`` while the link is up. A link that dates
        no connection (the simulations) is always live."""
        with self.lock:
            if self.connected_at is None:  # a simulation (a link that is down says so by its state)
                return True
            at = self.odom_at
            return at is not None and at >= self.connected_at and now - at < stale_s

    def set_report(self, msg: dict[str, Any]) -> None:
        arrival = time.monotonic()
        try:
            record = LatencyRecord.from_json(msg["data"])
        except (KeyError, TypeError, RecordError):
            return
        self.meter.on_report(record, arrival)
        with self.lock:
            self.latency_ms = record.latency_ms
            self.reports += 1

    def snapshot(self) -> tuple[Pose, float, float, float | None]:
        with self.lock:
            return self.pose, self.v, self.w, self.latency_ms


class Link(Protocol):
    """What every link does: its state, one command out, its telemetry in, closing. What some links do
    beyond that is a protocol of its own below, checked with ``isinstance`` (never probed by name)."""

    telemetry: Telemetry

    @property
    def state(self) -> str: ...

    def send(self, v: float, w: float) -> bool: ...

    def close(self) -> None: ...


@runtime_checkable
class Observes(Protocol):
    """A link that can feed an observer from the robot's own topics (observe mode)."""

    def observe(
        self, observer: Any, cmd: str, cmd_stamped: bool, plan: str, goal: str, status: str | None = None
    ) -> Callable[[], None]: ...


@runtime_checkable
class Echoes(Protocol):
    """A link that can echo any topic (the topics screen)."""

    def echo(
        self, topic: str, type_name: str, callback: Callable[[dict[str, Any]], None]
    ) -> Callable[[], None]: ...


@runtime_checkable
class Explains(Protocol):
    """A link that says why it is down, and why odometry does not come, in words."""

    topic_odom: str

    @property
    def error(self) -> str | None: ...

    @property
    def odometry_problem(self) -> str | None: ...


@runtime_checkable
class Stepped(Protocol):
    """A link whose robot is simulated in this process: stepped on the session's clock (50 Hz)."""

    def step(self) -> None: ...


ServiceDone = Callable[[bool, Any], None]  # (answered with a result, its values or the error text)


@runtime_checkable
class ReachesOthers(Protocol):
    """A link that can reach more than its own command path: a stop asks foreign controllers to stop
    through it (``control/stop.py``). Both calls return at once (False: the link is down) and never
    raise; ``done`` comes on the link's thread, or never (the caller bounds its wait)."""

    def call_service(
        self, service: str, args: dict[str, Any], timeout_s: float, done: ServiceDone
    ) -> bool: ...

    def publish_zero(self, topic: str, stamped: bool) -> bool: ...


class PendingLink:
    """The link before the real one exists (the first frame is painted before the backend starts):
    it sends nothing and reports ``STARTING``."""

    def __init__(self) -> None:
        self.telemetry = Telemetry()

    @property
    def state(self) -> str:
        return STARTING

    def send(self, v: float, w: float) -> bool:
        return False

    def close(self) -> None:
        pass
