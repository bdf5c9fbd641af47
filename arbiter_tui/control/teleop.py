"""Keyboard teleop as a pure state machine (teleop_twist_keyboard's key map and factors).

Most terminals send no key releases, so "held" means "pressed again soon enough": each key arrival
sets a deadline; while it lasts the command is repeated; when it passes, exactly one zero goes out.
How soon is "soon enough" is judged from the repeats as they arrive (docs/drive.md, "Over a jittery
link"), because over SSH on Wi-Fi they do not arrive at the terminal's pace:

* a fresh press holds for ``key_timeout`` (the terminal's initial repeat delay, 250-600 ms, comes
  before its first repeat); from then on a hold lasts ``GRACE_GAPS`` times the longest gap between the
  repeats seen lately (``GAPS_KEPT``), at least ``MIN_GRACE_S`` and at most ``key_timeout``: repeats
  bunched by a jittery link keep a steady hold without a gap, and when they really stop the zero goes
  out within that grace, not a fixed 0.6 s later;
* keys that arrive faster than any terminal repeats (more of them within ``PACE_WINDOW_S`` than
  ``MAX_REPEAT_HZ`` allows in the time they took, with ``PACE_SLACK_S`` of a link's jitter) were held
  back and replayed (a stall's burst, whether it comes in one read or split across several): where the
  hold they belong to has run out, it stays ended (one zero) and the rest are ignored; where it still
  runs and has been steady (``PACED_BEFORE_BURST`` repeats at a terminal's pace: a short stall, one lost
  packet's retransmission, 0.2-0.4 s), they are its repeats, late, and the hold goes on without a gap.
  After a dropped burst the hold resumes only with keys at a pace a terminal repeats at, and not on the
  first such key after a burst but on the one after it: TCP brings a stall's keys back in flights one
  round trip apart (its retransmission, then what its window held back), so a burst's next flight starts
  with a key at a hand's pace and the rest bunched behind it. A key sooner than ``FIRST_REPEAT_S`` after
  its press never makes a fresh hold steady (no terminal repeats that soon): the burst's first keys
  cannot extend it. So a stall's burst commands no motion after the person let go beyond the time its
  first keys took to arrive, and a stop key in it acts when it arrives, whatever came before or after it
  in the burst;
* the time of a key is when the terminal's input thread read it, taken before any lock (the session's
  ``key(name, at)``), so a lock held elsewhere never bunches or spreads the keys teleop judges;
* where the terminal reports key releases (:meth:`Teleop.release`), a hold ends at its release.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from arbiter_core.kinematics import DEFAULT_LIMITS, Limits

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
# The stop key that is never text: it stops from inside a text input too (where space and k type), on
# every screen and dialog (docs/drive.md, "Safety").
ANYWHERE_STOP = "ctrl+k"


def key_name(character: str | None, key: str) -> str:
    """The name teleop knows a key press by: its character when it prints one (``i``, ``,``, `` ``),
    else the terminal's key name (``up``, ``left``)."""
    return character if character and character.isprintable() else key


MIN_SPEED = 0.05  # m/s: z/x never scale the max speed below this (a robot that cannot move says nothing)
MIN_TURN = 0.05  # rad/s: likewise for c/z and the turn rate
# Where the movement keys sit on the keyboard (teleop_twist_keyboard's picture; k in the middle stops).
GRID = (("u", "i", "o"), ("j", "k", "l"), ("m", ",", "."))
AXIS_NAMES = {(True, True): ("both", "speed and turn"), (True, False): ("lin", "linear only"),
              (False, True): ("ang", "angular only")}  # fmt: skip
MODIFIER_KEYS = frozenset(
    {"shift", "left_shift", "right_shift", "ctrl", "left_ctrl", "right_ctrl", "alt", "left_alt", "right_alt",
     "meta", "left_meta", "right_meta", "super", "left_super", "right_super", "hyper", "caps_lock"}
)  # fmt: skip


def bounded(value: float, low: float, high: float) -> float:
    return max(low, min(value, high))


def cap_setting(name: str, value: float, limit: float, unit: str) -> tuple[float, str | None]:
    """A start speed or turn rate above the robot's limit is capped, and said once in words."""
    if value > limit:
        return limit, f"{name} {value:g} → {limit:g} {unit}, the robot's limit"
    return value, None


BUNCH_S = 0.01  # keys closer than this came together (no terminal repeats faster than 100 Hz)
# a hold outlasts its last repeat at least this long: TCP resends a lost key after at least 200 ms
# (Linux's least retransmission timeout) plus the link's round trip, and the gap it leaves is 0.26-0.33 s
# over lab Wi-Fi (at 0.25 s one lab hold in 14 had a cut-out: the first lost packet of a hold, before its gap
# had raised the grace); 0.15 s cut a hold on a paint or a collection while the suite loaded both cores
MIN_GRACE_S = 0.35
GRACE_GAPS = 2.0  # ...and this many times the longest recent gap between its repeats
GAPS_KEPT = 30  # recent gaps: a second of a 30 Hz auto-repeat
MAX_REPEAT_HZ = 60.0  # no terminal's auto-repeat is faster (30 Hz is a laptop's; 60 a fast X setting)
PACE_SLACK_S = 0.05  # a link's jitter may bunch keys this much closer than they were sent
PACE_WINDOW_S = 0.1  # the pace is judged over the keys of the hold that arrived this recently
FIRST_REPEAT_S = 0.1  # no terminal repeats a key this soon after its press (its initial delay)
ARRIVALS_KEPT = 32  # more keys than this in PACE_WINDOW_S is a replay whatever came before
# a burst is the hold's own keys, late, only in a hold that has had this many steady repeats at a
# terminal's pace (0.1 s of them at 30 Hz): a stall's burst comes back in TCP flights a round trip apart,
# and its second flight's first key, at a hand's pace after the first flight's, must not make the rest
# of that flight a live hold's repeats
PACED_BEFORE_BURST = 3


def too_fast(arrivals: deque[float], now: float) -> bool:
    """More keys arrived lately than a terminal's auto-repeat could have sent in the time they took
    (with a link's jitter allowed for): a replay of keys held back by a stall, however the burst was
    split across reads. ``arrivals``: the hold's recent arrival times, ``now`` the last."""
    for since, at in enumerate(reversed(arrivals)):  # ``since``: the keys after ``at``
        if now - at > PACE_WINDOW_S:
            break
        if since > (now - at + PACE_SLACK_S) * MAX_REPEAT_HZ:
            return True
    return False


FRESH, STEADY, STALE = "fresh", "steady", "stale"  # a hold's state: its first key, repeating, replayed
RESUMING = "resuming"  # after a burst, one key at a hand's pace: held if the next comes at that pace too


@dataclass
class Teleop:
    speed: float = 0.5
    turn: float = 1.0
    key_timeout: float = 0.6  # the longest a hold lasts after its last key (a fresh press: this long)
    limits: Limits = DEFAULT_LIMITS
    target: tuple[float, float] = (0.0, 0.0)
    deadline: float | None = None
    _zero_pending: bool = False
    _axes: tuple[int, int, int] = (0, 0, 0)
    _key: str | None = None  # the movement key of the current (or the last) hold
    _last_at: float = float("-inf")  # when it last arrived
    _state: str = FRESH
    gaps: deque[float] = field(default_factory=lambda: deque(maxlen=GAPS_KEPT))  # between steady repeats
    bursts: int = 0  # bursts replayed after a stall and cancelled (the bench and tests read it)
    _arrivals: deque[float] = field(default_factory=lambda: deque(maxlen=ARRIVALS_KEPT))  # this hold's
    _pressed_at: float = float("-inf")  # when this hold's key was pressed (its first arrival)
    _paced: int = 0  # this hold's repeats that came at a terminal's pace, one after another, steady

    def __post_init__(self) -> None:
        self.speed = bounded(self.speed, MIN_SPEED, self.limits.max_linear)
        self.turn = bounded(self.turn, MIN_TURN, self.limits.max_angular)

    @property
    def moving(self) -> bool:
        return self.deadline is not None

    def grace(self) -> float:
        """How long a steady hold outlasts its last repeat: from the gaps seen lately."""
        if not self.gaps:
            return self.key_timeout
        ceiling = self.key_timeout  # the user's: never more, even where it is under MIN_GRACE_S
        return bounded(GRACE_GAPS * max(self.gaps), min(MIN_GRACE_S, ceiling), ceiling)

    def press(self, key: str, now: float) -> str | None:
        """Handle one key; returns "move", "scale", "stop" or None (not a teleop key)."""
        if key in MODIFIER_KEYS:
            return None
        if key in MOVE_KEYS:
            self._move(key, now)
            return "move"
        if key in SCALE_KEYS:
            fs, ft = SCALE_KEYS[key]
            self.speed = bounded(self.speed * fs, MIN_SPEED, self.limits.max_linear)
            self.turn = bounded(self.turn * ft, MIN_TURN, self.limits.max_angular)
            if self.moving:
                self._retarget()
            return "scale"
        if key in STOP_KEYS:
            self.stop()
            return "stop"
        return None

    def _move(self, key: str, now: float) -> None:
        gap, self._last_at = now - self._last_at, now
        replayed = self._state in (STALE, RESUMING)
        if key != self._key or (self.deadline is None and not replayed) or gap > self.key_timeout:
            self._arrivals.clear()
            self._arrivals.append(now)
            self._pressed_at = now
            self._paced = 0
            self._hold(key, now, FRESH)  # a new key, or the same one pressed again after its hold ended
            return
        self._arrivals.append(now)
        live = self._paced >= PACED_BEFORE_BURST and self.deadline is not None and now < self.deadline
        # replayed from a stall (no hand sends keys this fast), after the hold ran out; a burst that
        # comes while the hold still runs is the hold's own keys, late (a lost packet's retransmission:
        # the deadman cut in on every one, a lurch every 15 s over lab Wi-Fi): repeats, as any late key
        if too_fast(self._arrivals, now) and not live:
            if self.deadline is not None:
                self.bursts += 1
                self.stop()
            self._state = STALE  # the rest of the burst ignored
            self._paced = 0
        elif replayed:
            if gap > self.grace():
                self._arrivals.clear()
                self._arrivals.append(now)
                self._pressed_at = now
                self._paced = 0
                self._hold(key, now, FRESH)  # long after the burst: pressed again
            elif gap < BUNCH_S:
                self._state = STALE  # bunched: the burst's next flight, still replayed
            elif self._state == STALE:
                self._state = RESUMING  # at a hand's pace after a burst: held if the next one is too
            else:  # the second key in a row at a terminal's pace: the key is still held
                self._hold(key, now, STEADY)
        elif self._state == FRESH and now - self._pressed_at < FIRST_REPEAT_S:
            pass  # sooner than a terminal's first repeat: the fresh hold's deadline stands (judged on)
        else:  # a repeat at a terminal's pace
            if self._state == STEADY and self.deadline is not None:
                self.gaps.append(gap)
                self._paced += gap >= BUNCH_S  # (keys that came together are no pace)
            self._hold(key, now, STEADY)

    def _hold(self, key: str, now: float, state: str) -> None:
        self._key, self._state = key, state
        self._axes = MOVE_KEYS[key]
        self._retarget()
        self.deadline = now + (self.key_timeout if state == FRESH else self.grace())
        self._zero_pending = False

    def release(self, key: str, now: float) -> bool:
        """The terminal reported ``key`` released (the kitty keyboard protocol's event types): its hold
        ends now (one zero). True if it ended a hold."""
        if key == self._key and self.deadline is not None:
            self.stop()
            return True
        return False

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


# -- the key legend, for the control screen and the help screen (one source: the tables above) ------
def grid_rows() -> list[str]:
    """``["u i o", "j k l", "m , ."]``"""
    return [" ".join(row) for row in GRID]


def scale_pairs() -> list[tuple[str, str, str, str]]:
    """(faster key, slower key, short name, long name) per axis group, in SCALE_KEYS order."""
    out = []
    for up, (fs, ft) in SCALE_KEYS.items():
        if max(fs, ft) <= 1.0:
            continue
        axes = (fs != 1.0, ft != 1.0)
        down = next(
            k for k, (ds, dt) in SCALE_KEYS.items() if (ds != 1.0, dt != 1.0) == axes and min(ds, dt) < 1.0
        )
        short, long = AXIS_NAMES[axes]
        out.append((up, down, short, long))
    return out


def factors() -> tuple[float, float]:
    """The scaling factors (up, down) of the keys that scale both speed and turn."""
    up, down = scale_pairs()[0][:2]
    return SCALE_KEYS[up][0], SCALE_KEYS[down][0]


def legend_compact() -> str:
    """The control screen's key panel (Rich markup)."""
    rows = grid_rows()
    scale = "  ".join(f"{up}/{down} {short}" for up, down, short, _ in scale_pairs())
    return (
        f"[b]Move[/b]   {rows[0]}\n"
        f"         {rows[1]}     k/space stop\n"
        f"         {rows[2]}     arrows too\n"
        f"[b]Scale[/b]  {scale}\n"
        "[b]Auto[/b]   a algorithm  n mission  g go"
    )


def legend_long() -> str:
    """The help screen's teleop lines."""
    up_f, down_f = factors()
    pairs = scale_pairs()
    first = f"{pairs[0][0]}/{pairs[0][1]}  {pairs[0][3]} x{up_f:g} / x{down_f:g}"
    rest = "  ".join(f"{up}/{down} {long}" for up, down, _, long in pairs[1:])
    return f"  {' / '.join(grid_rows())}   move;  arrows too;  k or space: stop\n  {first}   {rest}"


TELEOP_KEYS = frozenset(MOVE_KEYS) | frozenset(SCALE_KEYS) | STOP_KEYS  # all that teleop answers
