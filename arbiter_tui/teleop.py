"""Keyboard teleop as a pure state machine (teleop_twist_keyboard's key map and factors).

Terminals send no key releases, so "held" means "pressed again within
``key_timeout``": each press refreshes a deadline; while it lasts the command
is repeated; when it passes, exactly one zero goes out.
"""

from __future__ import annotations

from dataclasses import dataclass

from arbiter_backend.core.kinematics import DEFAULT_LIMITS, Limits

# key -> (x, y, th); y (holonomic) is carried for fidelity, a diff-drive robot ignores it.
MOVE_KEYS: dict[str, tuple[int, int, int]] = {
    "u": (1, 0, 1),
    "i": (1, 0, 0),
    "o": (1, 0, -1),
    "j": (0, 0, 1),
    "l": (0, 0, -1),
    "m": (-1, 0, -1),
    ",": (-1, 0, 0),
    ".": (-1, 0, 1),
    "U": (1, 1, 0),
    "I": (1, 0, 0),
    "O": (1, -1, 0),
    "J": (0, 1, 0),
    "L": (0, -1, 0),
    "M": (-1, 1, 0),
    "<": (-1, 0, 0),
    ">": (-1, -1, 0),
    "up": (1, 0, 0),
    "down": (-1, 0, 0),
    "left": (0, 0, 1),
    "right": (0, 0, -1),
}
SCALE_KEYS: dict[str, tuple[float, float]] = {
    "q": (1.1, 1.1),
    "z": (0.9, 0.9),
    "w": (1.1, 1.0),
    "x": (0.9, 1.0),
    "e": (1.0, 1.1),
    "c": (1.0, 0.9),
}
STOP_KEYS = frozenset({"k", " ", "space"})
MODIFIER_KEYS = frozenset(
    {"shift", "left_shift", "right_shift", "ctrl", "left_ctrl", "right_ctrl", "alt", "left_alt", "right_alt",
     "meta", "left_meta", "right_meta", "super", "left_super", "right_super", "hyper", "caps_lock"}
)  # fmt: skip


@dataclass
class Teleop:
    speed: float = 0.5
    turn: float = 1.0
    key_timeout: float = 0.6
    limits: Limits = DEFAULT_LIMITS
    target: tuple[float, float] = (0.0, 0.0)
    deadline: float | None = None
    _zero_pending: bool = False
    _axes: tuple[int, int, int] = (0, 0, 0)

    def __post_init__(self) -> None:
        self.speed = min(self.speed, self.limits.max_linear)
        self.turn = min(self.turn, self.limits.max_angular)

    @property
    def moving(self) -> bool:
        return self.deadline is not None

    def press(self, key: str, now: float) -> str | None:
        """Handle one key; returns "move", "scale", "stop" or None (not a teleop key)."""
        if key in MODIFIER_KEYS:
            return None
        if key in MOVE_KEYS:
            self._axes = MOVE_KEYS[key]
            self._retarget()
            self.deadline = now + self.key_timeout
            self._zero_pending = False
            return "move"
        if key in SCALE_KEYS:
            fs, ft = SCALE_KEYS[key]
            self.speed = min(self.speed * fs, self.limits.max_linear)
            self.turn = min(self.turn * ft, self.limits.max_angular)
            if self.moving:
                self._retarget()
            return "scale"
        if key in STOP_KEYS:
            self.stop()
            return "stop"
        return None

    def _retarget(self) -> None:
        x, _y, th = self._axes
        self.target = (x * self.speed, th * self.turn)

    def stop(self) -> None:
        """Stop now: the next tick sends exactly one zero."""
        self.target = (0.0, 0.0)
        self.deadline = None
        self._zero_pending = True

    def tick(self, now: float) -> tuple[float, float] | None:
        """The command to send at this tick, or None when idle (nothing to send)."""
        if self.deadline is not None:
            if now < self.deadline:
                return self.target
            self.stop()
        if self._zero_pending:
            self._zero_pending = False
            return (0.0, 0.0)
        return None
