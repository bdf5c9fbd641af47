"""This host's time-sync status (the probing; parsing and order are ``arbiter_core.timesync``'s).

Shared by the backend (``/api/health``) and the console (its own host): one probe, in the shared core
although it runs programs, because the two sides never import each other and it uses no I/O framework.

Read-only and unprivileged: ``chronyc -c tracking`` and ``timedatectl show`` with a short timeout,
then the ``adjtimex`` syscall with no modes set (Linux; via ctypes). A missing tool, a failure or a
timeout is "not this one", never an error. The answer is cached for ``max_age_s``: the status
changes slowly and a probe can take up to a second.
"""

from __future__ import annotations

import ctypes
import subprocess
import sys
import threading
import time

from arbiter_core import timesync
from arbiter_core.timesync import Adjtimex, TimeSync


def run(cmd: tuple[str, ...]) -> str | None:
    try:
        done = subprocess.run(
            cmd, capture_output=True, text=True, timeout=timesync.PROBE_TIMEOUT_S, check=False
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout if done.returncode == 0 else None


class _Timex(ctypes.Structure):
    # struct timex (linux/timex.h) up to the fields read, then room for the rest (it is 208 bytes)
    _fields_ = [
        ("modes", ctypes.c_uint),
        ("offset", ctypes.c_long),
        ("freq", ctypes.c_long),
        ("maxerror", ctypes.c_long),
        ("esterror", ctypes.c_long),
        ("status", ctypes.c_int),
        ("rest", ctypes.c_byte * 256),
    ]


def adjtimex() -> Adjtimex | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        tx = _Timex()  # modes 0: read only, no privilege needed
        state = libc.adjtimex(ctypes.byref(tx))
    except (OSError, AttributeError):
        return None
    if state < 0:
        return None
    return Adjtimex(state, tx.status, tx.maxerror, tx.esterror)


class HostClock:
    """The probe's last answer, refreshed when older than ``max_age_s``."""

    def __init__(self, max_age_s: float = 30.0) -> None:
        self.max_age_s = max_age_s
        self._lock = threading.Lock()
        self._probing = threading.Lock()
        self._value: TimeSync | None = None
        self._at = 0.0

    def read(self) -> TimeSync:
        """Blocking (up to ~2 s when probing): call it off the event loop."""
        with self._probing:  # one probe at a time: callers that come meanwhile take its answer
            now = time.monotonic()
            with self._lock:
                if self._value is not None and now - self._at < self.max_age_s:
                    return self._value
            value = timesync.probe(run, adjtimex)
            with self._lock:
                self._value, self._at = value, time.monotonic()
            return value

    def cached(self) -> TimeSync | None:
        with self._lock:
            return self._value
