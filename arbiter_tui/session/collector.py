"""Full garbage collections on the robot's clock: just after a command went out, never in the middle of
a control period.

CPython collects its oldest generation when enough young objects have survived, whatever thread is
running then, and holds the GIL for the whole walk. On the dashboard at 200x60 that walk covered
~40,000 objects (the strips alive in Textual's caches, seven caches each) plus ~4,000 a second of
cyclic garbage (strips kept in their own caches; ``shell/strips.py`` ends that), and on a Pi-class
CPU quota each one took 150-260 ms of wall time: one landing just before a control tick delayed that
command by as much (``bench/pi.py`` with ``bench/gcprobe``: every gap over 200 ms was one).

:class:`TickCollector` takes the oldest generation off the automatic schedule while the session's
thread runs, and collects it there instead, right after a control tick, once a ``period``, then freezes
what survived (:func:`collect_and_freeze`), so each walk covers only the objects made since the last:
0.5 ms instead of 150-260 ms on that dashboard, and it starts with the rest of a control period ahead of
it. The period is 0.2 s, not a second: in the first seconds of the analytics screen at 200x60 a second's
new objects took 60-150 ms of wall time to walk at a Pi-class quota, past the next command's time;
walks five times as often took 3-50 ms (``bench/pi.py`` with a tick probe, docs/BENCHMARKS.md session
18). Freezing more often froze ~2 % more objects, and their count was level after 30 s.
A frozen object that later ends in a cycle (a closed dialog's widgets) is freed by the next
whole-heap collection, which waits for a moment when the console sends no commands.
The young generations stay automatic (their collections are short). Thresholds are process-wide, so
the last session to stop restores what it found; nested sessions (tests run several) count.
"""

from __future__ import annotations

import gc
import threading
import time
from collections.abc import Callable

PERIOD_S = 0.2  # a full collection at most this often; at least this often while ticks run
# The whole heap, frozen part included, at most this often, and only once nothing was driven for QUIET_S.
# It walks every object (~180,000): 780-910 ms of wall time at a Pi-class quota (bench/gcprobe, the
# console idle at 200x60), during which a key waits. What it frees is little: frozen objects that later
# ended in a cycle, about one a second on the dashboard (docs/BENCHMARKS.md).
WHOLE_PERIOD_S = 300.0
QUIET_S = 10.0  # not right after a mission or a key: the user is likely to drive again soon
NEVER = 1 << 30  # a generation-2 threshold that the young collections never reach

_lock = threading.Lock()
_holders = 0
_saved: tuple[int, int, int] | None = None


def collect_and_freeze() -> None:
    """A full collection, then what survived moves to the permanent generation: the next full
    collection walks only what was made since, so it stays short however big the console's heap. A
    frozen object is still freed by reference counting when dropped (Textual's strips are, with
    ``shell/strips.py``); only one that later ends in a reference cycle stays (measured: the frozen
    count stays level over minutes on the dashboard, docs/BENCHMARKS.md)."""
    gc.collect()
    gc.freeze()


def collect_everything() -> None:
    """The whole heap, frozen part included: what ended in a cycle after it was frozen (a dialog
    closed, a notification gone) is freed here. As long as the heap is big, so only while idle."""
    gc.unfreeze()
    gc.collect()
    gc.freeze()


class TickCollector:
    """``after_tick`` runs on the session's thread after each control tick; ``begin``/``end`` bracket
    the thread's life. Once a ``period_s`` it collects what is not frozen (``collect``); once the
    console has sent no commands (``driving`` false) for ``quiet_s`` and ``whole_period_s`` has passed,
    the whole heap instead (``collect_all``), so nothing frozen stays uncollected past the next quiet
    spell.
    ``clock`` and the two collections are injected for tests."""

    def __init__(
        self,
        period_s: float = PERIOD_S,
        clock: Callable[[], float] = time.monotonic,
        collect: Callable[[], object] = collect_and_freeze,
        collect_all: Callable[[], object] = collect_everything,
        whole_period_s: float = WHOLE_PERIOD_S,
        quiet_s: float = QUIET_S,
    ) -> None:
        self.period_s = period_s
        self.whole_period_s = whole_period_s
        self.quiet_s = quiet_s
        self.clock = clock
        self.collect = collect
        self.collect_all = collect_all
        self.collections = 0  # full collections run after a tick (the bench and tests read it)
        self.whole_collections = 0  # of which over the whole heap
        self._last = self._last_whole = self._last_driving = clock()
        self._begun = False

    def begin(self) -> None:
        """Full collections happen only in :meth:`after_tick` from now until :meth:`end`."""
        global _holders, _saved
        with _lock:
            if self._begun:
                return
            self._begun = True
            if _holders == 0:
                _saved = gc.get_threshold()
                young, middle, _ = _saved
                gc.set_threshold(young, middle, NEVER)
            _holders += 1
        self._last = self.clock()

    def due(self) -> bool:
        """A collection would run at the next :meth:`after_tick`."""
        return self._begun and self.clock() - self._last >= self.period_s

    def after_tick(self, driving: bool = True) -> bool:
        """Collect every generation if a period has passed since the last time; True when it did.
        ``driving``: the console is sending commands (a mission, a held key), so no whole-heap walk."""
        if not self._begun:
            return False
        now = self.clock()
        if driving:
            self._last_driving = now
        if now - self._last < self.period_s:
            return False
        self._last = now
        quiet = not driving and now - self._last_driving >= self.quiet_s
        if quiet and now - self._last_whole >= self.whole_period_s:
            self._last_whole = now
            self.collect_all()
            self.whole_collections += 1
        else:
            self.collect()
        self.collections += 1
        return True

    def end(self) -> None:
        """Give the oldest generation back to the automatic schedule (when no other session holds it)."""
        global _holders, _saved
        with _lock:
            if not self._begun:
                return
            self._begun = False
            _holders -= 1
            if _holders == 0 and _saved is not None:
                gc.set_threshold(*_saved)
                _saved = None
