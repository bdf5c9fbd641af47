"""Teleop keys that do not wait for a paint: taken on Textual's input thread, in order.

Under a Pi-class CPU quota a paint in progress held a key 20-45 ms (bench/pi.py, key-to-wire), and the
robot should not wait for the screen. A teleop key (movement, scale, stop) on the control screen goes to
the session at once, on the driver's input thread; it still goes on to the UI, marked as answered, so
the screen shows it and nothing answers it twice. Keys keep their order: while a key the UI must answer
(g, a, 1, ...) is queued and not yet handled, the keys after it queue behind it.

The stop key that is never text (``ctrl+k``) is answered on the input thread whatever is in front, a
dialog or a text input included, and then again by the UI in its place among the keys (a ``g`` queued
before it must not start a mission after it).
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


class KeyRouter:
    """Which keys the session answers on the input thread, and which the UI answers (thread-safe)."""

    def __init__(
        self,
        answer: Callable[[str], bool],
        stop: Callable[[], None] = lambda: None,
        reported: Callable[[float], None] = lambda now: None,
    ) -> None:
        self._answer = answer  # the session's key handler: True if it used the key
        self._stop = stop  # the session's stop (ANYWHERE_STOP, on the input thread)
        self.reported = reported  # the terminal answered a cursor query (session/heartbeat.py), at ``now``
        self._lock = threading.Lock()
        self._direct = False  # the control screen is in front, no dialog over it, no key queued
        self._queued = 0  # keys passed to the UI that it has not answered yet
        self._taken: set[int] = set()  # ids of key events the session already answered

    def set_direct(self, direct: bool) -> None:
        """The control screen came to the front (True) or went behind a screen or dialog (False)."""
        with self._lock:
            self._direct = direct

    def on_input_thread(self, event: events.Key) -> None:
        """A key on Textual's input thread, before it joins the UI's queue."""
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
            used = self._answer(key)
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
STOP_BINDINGS = [
    # priority: a dialog, a table or a button never takes them first; space and k are text in a text
    # input (the app's check_action then passes them on), ctrl+k never is
    Binding("space", f"stop('{NOT_TEXT}')", "Stop", priority=True),
    Binding("k", f"stop('{NOT_TEXT}')", "Stop", show=False, priority=True),
    Binding(ANYWHERE_STOP, "stop", "Stop", show=False, priority=True),
]
# what a dialog's footer shows (the app's priority bindings above answer the keys first)
STOP_HINT = Binding(ANYWHERE_STOP, "app.stop", "Stop robot", key_display="space/^k", priority=True)
STOP_HINT_TYPING = Binding(ANYWHERE_STOP, "app.stop", "Stop robot", key_display="^k", priority=True)
