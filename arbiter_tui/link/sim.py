"""The client-side simulation link: no network, the simulator steps inside the console's process."""

from __future__ import annotations

import time
from collections.abc import Callable

from arbiter_core.simulator import DiffDriveSimulator

from .base import SIMULATED, Telemetry


class SimLink:
    """Client-side simulation: no network, the simulator steps inside the TUI process; no latency."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self.telemetry = Telemetry()
        self.sim = DiffDriveSimulator()
        self._clock = clock

    @property
    def state(self) -> str:
        return SIMULATED

    def send(self, v: float, w: float) -> bool:
        self.sim.on_twist({"linear": {"x": v}, "angular": {"z": w}}, self._clock())
        return True

    def step(self) -> None:
        odom = self.sim.tick(self._clock(), time.time_ns())
        self.telemetry.set_odom(odom)

    def close(self) -> None:
        pass
