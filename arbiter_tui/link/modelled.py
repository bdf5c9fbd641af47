"""The client-side simulator behind a modelled link (``arbiter_core.linkmodel``), in simulated time.

Commands reach the robot after the model's latency and jitter (some never); the simulator integrates
up to each command's arrival before taking it, so a command sent at ``t`` acts from ``t + delay``
exactly. Odometry reaches the console ``odom_delay`` after the robot was there; ``true_pose`` is where
the robot is now (what tracking error is measured against).
"""

from __future__ import annotations

import random
import time
from collections.abc import Callable
from typing import Any

from arbiter_core.kinematics import Pose
from arbiter_core.linkmodel import DelayLine, LinkModel
from arbiter_core.simulator import DiffDriveSimulator

from .base import SIMULATED, Telemetry


def _twist(v: float, w: float) -> dict[str, Any]:
    return {"linear": {"x": v}, "angular": {"z": w}}


class ModelledLink:
    def __init__(
        self, model: LinkModel, clock: Callable[[], float], seed: int = 0, cmd_timeout: float = 0.5
    ) -> None:
        self.model = model
        self.telemetry = Telemetry()  # what the console sees: odometry as late as the model says
        self.sim = DiffDriveSimulator(cmd_timeout=cmd_timeout)  # stops when commands stop arriving
        self._clock = clock
        rng = random.Random(seed)
        self.commands: DelayLine[tuple[float, float]] = DelayLine(
            model.latency_s, model.jitter_s, model.loss, rng
        )
        self.odometry: DelayLine[dict[str, Any]] = DelayLine(model.odom_delay_s)

    @property
    def state(self) -> str:
        return SIMULATED

    @property
    def true_pose(self) -> Pose:
        return self.sim.state.pose

    def send(self, v: float, w: float) -> bool:
        self.commands.send(self._clock(), (v, w))
        return True

    def step(self) -> None:
        now = self._clock()
        for at, (v, w) in self.commands.due(now):
            self.sim.tick(at, 0)  # the robot moves under the old command until this one arrives
            self.sim.on_twist(_twist(v, w), at)
        odom = self.sim.tick(now, time.time_ns())
        self.odometry.send(now, odom)
        for _, arrived in self.odometry.due(now):
            self.telemetry.set_odom(arrived)

    def close(self) -> None:
        pass
