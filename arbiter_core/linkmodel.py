"""A modelled link for simulated runs: commands reach the robot late (latency, jitter), some never
(loss); odometry reaches the console late. Pure; time is the caller's (simulated) clock.

Jitter is half-normal: each command's delay is ``latency + |N(0, jitter)|`` — never earlier than the
fixed latency, with the long tail of a busy Wi-Fi link. Delivery is in order, as over rosbridge's TCP
connection: a command never overtakes the one sent before it (it waits behind it instead).
"""

from __future__ import annotations

import math
import random
from collections import deque
from dataclasses import dataclass
from typing import Generic, TypeVar

T = TypeVar("T")


class LinkModelError(ValueError):
    """A link parameter that cannot be (negative, not finite, loss of 1 or more)."""


@dataclass(frozen=True)
class LinkModel:
    latency_s: float = 0.0  # one way, console -> robot
    jitter_s: float = 0.0  # scale of the half-normal extra delay
    loss: float = 0.0  # fraction of commands that never arrive
    odom_delay_s: float = 0.0  # robot -> console

    def __post_init__(self) -> None:
        for name in ("latency_s", "jitter_s", "loss", "odom_delay_s"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise LinkModelError(f"{name} must be a finite number >= 0, got {v!r}")
        if self.loss >= 1.0:
            raise LinkModelError(f"loss must be below 1, got {self.loss!r}")

    @property
    def perfect(self) -> bool:
        return self == LinkModel()

    def as_dict(self) -> dict[str, float]:
        return {
            "latency_ms": self.latency_s * 1e3,
            "jitter_ms": self.jitter_s * 1e3,
            "loss": self.loss,
            "odom_delay_ms": self.odom_delay_s * 1e3,
        }


class DelayLine(Generic[T]):
    """Items sent at ``t`` come out at ``t + delay`` (see the module), in order, some dropped."""

    def __init__(
        self, latency_s: float, jitter_s: float = 0.0, loss: float = 0.0, rng: random.Random | None = None
    ) -> None:
        self.latency_s, self.jitter_s, self.loss = latency_s, jitter_s, loss
        self.rng = rng or random.Random(0)
        self._queue: deque[tuple[float, T]] = deque()
        self._last = -math.inf
        self.sent = 0
        self.dropped = 0

    def send(self, t: float, item: T) -> float | None:
        """Queue ``item`` sent at ``t``; its arrival time, or None when the link drops it."""
        self.sent += 1
        if self.loss and self.rng.random() < self.loss:
            self.dropped += 1
            return None
        delay = self.latency_s + (abs(self.rng.gauss(0.0, self.jitter_s)) if self.jitter_s else 0.0)
        at = max(t + delay, self._last)
        self._last = at
        self._queue.append((at, item))
        return at

    def due(self, t: float) -> list[tuple[float, T]]:
        """Everything that has arrived by ``t``, with its arrival time, oldest first."""
        out = []
        while self._queue and self._queue[0][0] <= t:
            out.append(self._queue.popleft())
        return out
