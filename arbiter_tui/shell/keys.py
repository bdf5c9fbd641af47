"""Teleop keys that do not wait for a paint: taken on Textual's input thread, in order.

Under a Pi-class CPU quota a paint in progress held a key 20-45 ms (bench/pi.py, key-to-wire), and the
robot should not wait for the screen. A teleop key (movement, scale, stop) on the control screen goes to
the session at once, on the driver's input thread; it still goes on to the UI, marked as answered, so
the screen shows it and nothing answers it twice. Keys keep their order: while a key the UI must answer
(g, a, 1, ...) is queued and not yet handled, the keys after it queue behind it.

The stop key that is never text (``ctrl+k``) is answered on the input thread whatever is in front, a
dialog or a text input included, and then again by the UI in its place among the keys (a ``g`` queued
before it must not start a mission after it).

A key's time is when the input thread read it (``KeyRouter.read_at``), taken there before any lock and
passed down: teleop judges a burst by the keys' spacing, and a lock held elsewhere (the session's, while
a key before it waits) must neither spread a burst's keys nor bunch a hand's.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from textual import events
from textual.binding import Binding
from textual.driver import Driver
from textual.message import Message

from ..control.teleop import ANYWHERE_STOP, TELEOP_KEYS, key_name

log = logging.getLogger(__name__)


SAME_READ_S = 0.0005  # a key made this soon after the one before it was answered came in the same read
READ_AT = "arbiter_read_at"  # the attribute a key event carries its read time on, for the UI's thread


class KeyRouter:
    """Which keys the session answers on the input thread, and which the UI answers (thread-safe)."""

    def __init__(
        self,
        answer: Callable[[str, float], bool],
        stop: Callable[[], None] = lambda: None,
        clock: Callable[[], float] = time.monotonic,
        stamp: Callable[[], float] = time.monotonic,
        reported: Callable[[float], None] = lambda now: None,
    ) -> None:
        self._answer = answer  # the session's key handler (the key, when it was read): True if it used it
        self._stop = stop  # the session's stop (ANYWHERE_STOP, on the input thread)
        self._clock = clock  # the session's clock, the one a key's time is given on
        self._stamp = stamp  # the clock Textual stamps each event with as it makes it (monotonic)
        self.reported = reported  # the terminal answered a cursor query (session/heartbeat.py), at ``now``
        self._lock = threading.Lock()
        self._direct = False  # the control screen is in front, no dialog over it, no key queued
        self._queued = 0  # keys passed to the UI that it has not answered yet
        self._taken: set[int] = set()  # ids of key events the session already answered
        self._read = (float("-inf"), float("-inf"))  # (stamp, read time) of the last key's read
        self._done = float("-inf")  # when the input thread was done with the last key (stamp)

    def read_at(self, event: events.Key) -> float:
        """When ``event``'s read came, on the session's clock (the input thread, before any lock). The
        parser makes a read's keys one after another as the input thread answers them, so a key made
        right after the one before it was answered is of the same read and gets that read's time, not
        one later by what answering the keys before it took (a lock waited on, a stop sent)."""
        now = self._stamp()
        made = getattr(event, "time", now)
        read = self._read[1] if made - self._done < SAME_READ_S and made >= self._done else made
        self._read = (made, read)
        return self._clock() - max(0.0, now - read)

    def when(self, event: events.Key) -> float:
        """The UI's thread: when ``event``'s read came, as the input thread took it (now, on the
        session's clock, for a key that did not come through it)."""
        at = getattr(event, READ_AT, None)
        return at if isinstance(at, float) else self._clock()

    def set_direct(self, direct: bool) -> None:
        """The control screen came to the front (True) or went behind a screen or dialog (False)."""
        with self._lock:
            self._direct = direct

    def on_input_thread(self, event: events.Key) -> None:
        """A key on Textual's input thread, before it joins the UI's queue."""
        try:
            self._on_input_thread(event)
        finally:
            self._done = self._stamp()

    def _on_input_thread(self, event: events.Key) -> None:
        at = self.read_at(event)  # first: before any lock
        setattr(event, READ_AT, at)  # for the UI, if it answers the key
        key = key_name(event.character, event.key)
        if key == ANYWHERE_STOP:
            try:
                self._stop()
            except Exception:  # the UI answers it too, below
                log.exception("a stop on the input thread failed")
            with self._lock:
                self._queue()
            return
        with self._lock:
            take = self._direct and self._queued == 0 and key in TELEOP_KEYS
            if not take:
                self._queue()
        if not take:
            return
        try:
            used = self._answer(key, at)
        except Exception:  # never let a key take the input thread down: the UI gets it instead
            log.exception("a key on the input thread failed")
            used = False
        with self._lock:
            if used:
                self._taken.add(id(event))
            else:
                self._queue()

    def _queue(self) -> None:
        """A key goes to the UI (under the lock): the keys after it wait for it, and until the UI has
        answered it nothing goes direct (it may open a dialog, or leave the control screen)."""
        self._queued += 1
        self._direct = False

    def taken(self, event: events.Key) -> bool:
        """The UI's thread: was ``event`` already answered on the input thread? (Asked once per key.)"""
        with self._lock:
            taken = id(event) in self._taken
            self._taken.discard(id(event))
        return taken

    def handled(self, control_in_front: bool) -> None:
        """The UI answered a key it was passed; ``control_in_front``: the control screen is still in
        front with no dialog over it."""
        with self._lock:
            self._queued = max(0, self._queued - 1)
            if self._queued == 0 and control_in_front:
                self._direct = True


def direct_keys(base: type[Driver], router: Callable[[], KeyRouter | None]) -> type[Driver]:
    """``base`` (the terminal driver Textual chose) with keys offered to ``router()`` on the driver's
    input thread, before they join the UI's queue, and the terminal's answers to the heartbeat's cursor
    queries (``shell/operator.py``) handed to it there, never queued behind a paint."""

    class DirectKeysDriver(base):  # type: ignore[misc, valid-type]  # the driver Textual chose at run time
        def process_message(self, message: Message) -> None:
            keys = router()
            if isinstance(message, events.CursorPosition) and keys is not None:
                keys.reported(time.monotonic())  # the heartbeat's answer: the app never needs it
                return
            if isinstance(message, events.Key) and keys is not None:
                keys.on_input_thread(message)
            super().process_message(message)

    DirectKeysDriver.__name__ = f"DirectKeys{base.__name__}"
    return DirectKeysDriver


# -- the stop keys' bindings (one definition: the app's, and what every dialog's footer shows) ------------
NOT_TEXT = "not_text"  # the stop's parameter for the keys that are text in a text input
TYPING = "typing"  # ... and for ctrl+k's binding the footer shows while a text input has the focus
STOP_BINDINGS = [
    # priority: a dialog, a table or a button never takes them first; space and k are text in a text
    # input (the app's check_action then passes them on), ctrl+k never is
    Binding("space", f"stop('{NOT_TEXT}')", "Stop", priority=True),
    Binding("k", f"stop('{NOT_TEXT}')", "Stop", show=False, priority=True),
    # while typing (the topics filter), where space and k are text, the footer names ctrl+k instead; the
    # app's check_action enables this one only then, and the next one answers ctrl+k everywhere else
    Binding(ANYWHERE_STOP, f"stop('{TYPING}')", "Stop robot", key_display="^k", priority=True),
    Binding(ANYWHERE_STOP, "stop", "Stop", show=False, priority=True),
]
# what a dialog's footer shows (a modal dialog's footer shows its own bindings, not the app's; the app's
# priority bindings above answer the keys first): space/^k, or ^k in a dialog one types in
STOP_HINT = Binding(ANYWHERE_STOP, "app.stop", "Stop robot", key_display="space/^k", priority=True)
STOP_HINT_TYPING = Binding(ANYWHERE_STOP, "app.stop", "Stop robot", key_display="^k", priority=True)
