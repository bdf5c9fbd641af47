"""Does the person's terminal still hear the console? Its answers to a query written in the screen's own
byte stream say so (docs/drive.md, "An operator who cannot see").

The shell writes a Cursor Position Report request (``ESC [ 6 n``) behind its frames every
``PERIOD_S``; the person's terminal answers ``ESC [ row ; col R`` over the same SSH link, which Textual's
parser already turns into an event (a Device Status Report's ``ESC [ 0 n`` it does not know: it reissues
it as the keys ``[``, ``0``, ``n``, and ``n`` selects the next mission). An answer says the terminal has
read everything written before the query: the person's screen is at most one round trip old. No answer
for longer than the bound (``--operator-timeout``) and the session holds what drives on its own
(``OperatorWatch``), on its own thread: a blocked screen never delays the judgement.

Under a multiplexer the answers come from the multiplexer, not from the person's terminal: tmux is asked
instead whether a client is attached (``tmux_attached``); GNU screen offers nothing cheap (said once).

Pure logic and a lock: the UI thread asks, the input thread hears, the session's thread judges.
"""

from __future__ import annotations

import logging
import threading
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass

log = logging.getLogger(__name__)

QUERY = "\x1b[6n"  # Cursor Position Report request (every VT100 descendant, tmux and screen answer it)
PERIOD_S = 0.25  # a query every quarter second: ~160 bytes a second both ways
PROBE_S = 3.0  # no answer this long after the first query: the terminal does not answer them
TMUX_PERIOD_S = 1.0  # tmux asked once a second (a process each time: off the UI thread)
TERMINAL, TMUX = "terminal", "tmux"  # who answers

PROBING, SILENT, HEARD, UNHEARD = "probing", "silent", "heard", "unheard"


def multiplexer(env: Mapping[str, str]) -> str | None:
    """The multiplexer the console runs under, from its environment (tmux sets $TMUX, screen $STY)."""
    if env.get("TMUX"):
        return TMUX
    if env.get("STY"):
        return "screen"
    return None


def tmux_attached(out: str) -> bool | None:
    """``tmux display -p '#{session_attached}'``'s answer: is a client attached? None: no answer."""
    try:
        return int(out.strip()) > 0
    except ValueError:
        return None


class Heartbeat:
    """The answers to the queries, and the verdict: ``PROBING`` until the first answer (``SILENT`` once
    ``probe_s`` passed without one), then ``HEARD`` while the last answer is at most ``timeout_s`` old,
    ``UNHEARD`` beyond. Thread-safe."""

    def __init__(self, timeout_s: float, source: str = TERMINAL, probe_s: float = PROBE_S) -> None:
        self.timeout_s = timeout_s
        self.source = source
        self.probe_s = probe_s
        self._lock = threading.Lock()
        self._first: float | None = None  # the first query
        self._heard: float | None = None  # the last answer
        self._pending: deque[float] = deque(maxlen=64)  # queries not answered yet, oldest first
        self._rtt: deque[float] = deque(maxlen=8)

    def asked(self, now: float) -> None:
        """A query was written (or tmux asked)."""
        with self._lock:
            if self._first is None:
                self._first = now
            self._pending.append(now)

    def heard(self, now: float) -> None:
        """An answer came (or tmux said a client is attached)."""
        with self._lock:
            self._heard = now
            if self._pending:
                self._rtt.append(now - self._pending.popleft())

    def verdict(self, now: float) -> str:
        with self._lock:
            if self._heard is None:
                return SILENT if self._first is not None and now - self._first >= self.probe_s else PROBING
            return UNHEARD if now - self._heard > self.timeout_s else HEARD

    def silent_for(self, now: float) -> float:
        """How long since the last answer (0 before any)."""
        with self._lock:
            return 0.0 if self._heard is None else now - self._heard

    def round_trip_s(self) -> float | None:
        """The longest of the recent round trips (query written to answer read), None before any."""
        with self._lock:
            return max(self._rtt) if self._rtt else None

    def lag_s(self, now: float) -> float | None:
        """How late the screen is now: the last answer's round trip, or longer while the oldest query
        waits for its answer (None before any answer)."""
        with self._lock:
            if not self._rtt:
                return None
            waiting = now - self._pending[0] if self._pending else 0.0
            return max(self._rtt[-1], waiting)


@dataclass(frozen=True)
class OperatorLost:
    """No answer for longer than the bound while something drove on its own: it holds."""

    held: str
    silent_s: float


@dataclass(frozen=True)
class OperatorBack:
    """Answers again after ``silent_s`` without; ``held``: what held meanwhile (g resumes it)."""

    held: str | None
    silent_s: float

    def text(self) -> str:
        out = f"your terminal did not answer for {self.silent_s:.1f} s"
        if self.held is None:
            return out + ": nothing drove on its own"
        return f"{out}: {self.held} held (zero command). Press g to resume"


@dataclass(frozen=True)
class OperatorUnknown:
    """The console cannot tell whether the person sees it (said once, at start)."""

    text: str


def unknown_words(source: str | None) -> str:
    """Why the console cannot tell, in words, for the source that did not answer (or the multiplexer)."""
    tail = ": a mission drives on through a stalled link until sshd hangs up (docs/drive.md)"
    if source == TERMINAL:
        return f"this terminal did not answer the console's cursor queries in {PROBE_S:g} s{tail}"
    if source == TMUX:
        return "no tmux client has been attached since the start (or tmux did not answer)" + tail
    return f"under {source} the console cannot tell whether anyone sees it{tail}"


class OperatorWatch:
    """The session's side (its thread, under its lock): each control tick asks :meth:`hold` whether what
    drives on its own must hold now; the transitions are told (``say``) once each."""

    def __init__(self, timeout_s: float, say: Callable[[object], None]) -> None:
        self.timeout_s = timeout_s  # 0: off
        self.heartbeat: Heartbeat | None = None
        self._say = say
        self._unknown_said = False
        self._lost: float | None = None  # since when no answer came, once judged unheard
        self._held: str | None = None

    def arm(self, heartbeat: Heartbeat | None, unknown: str | None = None) -> None:
        """The shell's choice: answers to judge (None: none; ``unknown`` says why, once)."""
        self.heartbeat = heartbeat if self.timeout_s > 0 else None
        if unknown is not None and self.timeout_s > 0:
            self._unknown_said = True
            log.warning("%s", unknown)
            self._say(OperatorUnknown(unknown))

    def heard(self, now: float) -> None:
        if (hb := self.heartbeat) is not None:
            hb.heard(now)

    def hold(self, now: float, driving: str | None) -> bool:
        """True while no answer has come for longer than the bound and ``driving`` (what drives on its own,
        in words; None: nothing) must hold."""
        hb = self.heartbeat
        if hb is None:
            return False
        verdict = hb.verdict(now)
        if verdict == SILENT and not self._unknown_said:
            self._unknown_said = True
            log.warning("%s", unknown_words(hb.source))
            if hb.source == TERMINAL:  # (a tmux session nobody attached to has nobody to tell)
                self._say(OperatorUnknown(unknown_words(hb.source)))
        if verdict == UNHEARD:
            if self._lost is None:
                self._lost = now - hb.silent_for(now)
            if driving is not None:
                self._held = self._held or driving
                log.warning("the terminal has not answered for %.1f s: %s holds", now - self._lost, driving)
                self._say(OperatorLost(driving, now - self._lost))
                return True
            return False
        if verdict == HEARD and self._lost is not None:
            log.warning("the terminal answers again after %.1f s (held: %s)", now - self._lost, self._held)
            self._say(OperatorBack(self._held, now - self._lost))
            self._lost, self._held = None, None
        return False
