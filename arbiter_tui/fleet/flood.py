"""A robot's payloads over its kind's rate: the excess dropped before it is copied or parsed, and the row
marked "flooding: N/s". Pure: no Zenoh, no clock (monotonic seconds are passed in).

Each kind may come ``FLOOD_FACTOR`` times its period's rate (``arbiter_core.fleet.PERIOD_S``: a status a
second may come four a second) after a burst of ``BURST`` (a robot that connects sends every kind at
once): a token bucket per robot and kind. What arrives is counted over windows of a second; the rate
of a window in which payloads were dropped is the one the row shows, for ``FLOOD_HOLD_S`` after the
last drop.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from arbiter_core import fleet

FLOOD_FACTOR = 4.0
BURST = 3.0
FLOOD_HOLD_S = 10.0
WINDOW_S = 1.0


@dataclass(slots=True)
class Meter:
    """One robot's payloads: what may pass now, and how fast they came while some were dropped."""

    tokens: dict[str, float] = field(default_factory=dict)
    at: dict[str, float] = field(default_factory=dict)
    window_start: float | None = None
    arrivals: int = 0
    window_dropped: int = 0
    dropped: int = 0  # since the console started
    last_drop: float | None = None
    flood_rate: float = 0.0  # payloads a second over the last window in which some were dropped

    def admit(self, kind: str, mono: float) -> bool:
        """One payload of ``kind`` arrived: may it be parsed (True), or is it over the rate (dropped)?"""
        self._count(mono)
        limit = FLOOD_FACTOR / fleet.PERIOD_S[kind]
        have = self.tokens.get(kind, BURST)
        have = min(BURST, have + (mono - self.at.get(kind, mono)) * limit)
        self.at[kind] = mono
        if have >= 1.0:
            self.tokens[kind] = have - 1.0
            return True
        self.tokens[kind] = have
        self.dropped += 1
        self.window_dropped += 1
        self.last_drop = mono
        return False

    def _count(self, mono: float) -> None:
        if self.window_start is None:
            self.window_start = mono
        elif mono - self.window_start >= WINDOW_S:
            if self.window_dropped:
                self.flood_rate = self.arrivals / (mono - self.window_start)
            self.window_start, self.arrivals, self.window_dropped = mono, 0, 0
        self.arrivals += 1

    def flooding(self, mono: float) -> float | None:
        """The rate it floods at (payloads a second), while it does and FLOOD_HOLD_S after; else None."""
        if self.last_drop is None or mono - self.last_drop > FLOOD_HOLD_S:
            return None
        if self.window_start is not None and self.window_dropped and mono - self.window_start > 0:
            return max(self.flood_rate, self.arrivals / max(mono - self.window_start, WINDOW_S))
        return self.flood_rate
