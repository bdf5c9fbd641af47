"""Messages one node of this process handed to another directly, whose DDS copy is still to come.

The relay and the tracker share a process: commands and reports go between them in-process, and
are still published on DDS for every other node. The receiver then skips the DDS copy of a text it
already handled. Counted by text, so a sender that sends the same text twice is handled twice;
bounded, so copies that never come (nobody subscribed on DDS) cannot grow it.
"""

from __future__ import annotations

import threading

MEMORY = 10_000  # texts remembered (a few seconds at any real command rate)


class HandledLocally:
    def __init__(self, memory: int = MEMORY) -> None:
        self._pending: dict[str, int] = {}
        self._lock = threading.Lock()
        self._memory = memory
        self.skipped = 0  # DDS copies not handled a second time

    def note(self, text: str) -> None:
        """``text`` was handled in-process; its DDS copy will be skipped once."""
        with self._lock:
            self._pending[text] = self._pending.get(text, 0) + 1
            if len(self._pending) > self._memory:
                del self._pending[next(iter(self._pending))]

    def take(self, text: str) -> bool:
        """True (and forgotten once) when ``text`` is the DDS copy of something already handled."""
        if not self._pending:  # the common case without in-process traffic: no lock
            return False
        with self._lock:
            left = self._pending.get(text)
            if not left:
                return False
            if left == 1:
                del self._pending[text]
            else:
                self._pending[text] = left - 1
            self.skipped += 1
            return True
