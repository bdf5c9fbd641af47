"""The analytics screen's error-vs-latency curve: ``arbiter-tui compare`` in a child process.

A child process, not a thread: the sweep is pure Python, and in a thread it would hold the GIL the
console's control loop needs (the robot's commands would wait behind it). The child runs at a lower
priority (``nice``), so on a Raspberry Pi-class CPU the console keeps its core.

``nice`` orders CPU only among processes that share a quota: under a cgroup quota (a Pi stand-in) the
child still spends the console's, and the control loop waits for the next period. So the sweep, which is
deterministic (seeded, simulated time), runs **once per setting**: its answer is kept under the user's
cache directory (``platformdirs``: ``~/.cache/arbiter-tui/sweeps`` on Linux), keyed by its command
and a fingerprint of the code that computes it (controllers, simulator, link model, compare), and every
later session reads the file instead of running the child. A damaged file is computed again.

The first sweep of a setting (and the first after the code changed) still has to run somewhere. On a
console with no core to spare (``cpu_share.cores_available`` under ``SPARE_CORES``: one CPU, or a
cgroup quota) :class:`SweepPause` stops the child (``SIGSTOP``) while the robot drives and lets it go
on (``SIGCONT``) once the robot has stood still for ``RESUME_S``: the sweep then costs the robot
nothing, and the analytics screen says it waits. With a core to spare the child just runs, niced.
The child dies with the console (``PR_SET_PDEATHSIG``): a stopped orphan would wait forever.
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import functools
import hashlib
import json
import os
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

from ..analytics.linkcurve import SWEEP_LATENCIES_MS, CurveError, LinkCurve, curve_of
from .cpu_share import SPARE_CORES

NICE = 10
TIMEOUT_S = 120.0  # of the child's running time (not the time it was paused)
RESUME_S = 1.0  # still this long, the robot lets a paused sweep go on
POLL_S = 0.25  # how often the wait for the child looks at the clock
_MAIN = "import sys; from arbiter_tui.cli import main; sys.exit(main(sys.argv[1:]))"


def command(mission: str, speed: float, turn: float) -> list[str]:
    latencies = ",".join(f"{ms:g}" for ms in SWEEP_LATENCIES_MS)
    return [
        sys.executable, "-c", _MAIN, "compare", "--json", "--mission", mission, "--latency", latencies,
        "--speed", f"{speed:g}", "--turn", f"{turn:g}",
    ]  # fmt: skip


# what the sweep's answer depends on besides its command: a change to any of these computes it afresh
_CODE = ("arbiter_tui/control", "arbiter_tui/session", "arbiter_tui/analytics", "arbiter_core")


@functools.cache
def fingerprint() -> str:
    """A hash of the source of everything the sweep runs (read once per process, ~60 small files)."""
    root = Path(__file__).resolve().parent.parent.parent
    h = hashlib.sha256()
    for folder in _CODE:
        for path in sorted((root / folder).glob("*.py")):
            h.update(path.name.encode())
            h.update(path.read_bytes())
    return h.hexdigest()[:16]


def cache_dir() -> Path:
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("arbiter-tui")) / "sweeps"


def cache_path(mission: str, speed: float, turn: float) -> Path:
    args = command(mission, speed, turn)[3:]  # the subcommand and its arguments, not the interpreter
    key = hashlib.sha256(json.dumps([fingerprint(), args]).encode()).hexdigest()[:24]
    return cache_dir() / f"{mission}-{key}.json"


def _cached(path: Path, mission: str) -> LinkCurve | None:
    try:
        return curve_of(json.loads(path.read_text()), mission)
    except (OSError, ValueError, CurveError):
        return None  # absent or damaged: computed again


def _keep(path: Path, body: bytes) -> None:
    """Written whole or not at all (a temporary file renamed); a cache that cannot be written is no error."""
    with contextlib.suppress(OSError):
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(body)
            os.replace(tmp, path)
        finally:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


class SweepPause:
    """Holds the sweep's child while the robot drives, where the console has no core to spare.

    ``driving`` runs on the session's thread after every control tick; ``child`` on the UI's when the
    child starts and ends. The signal goes out on a change only (and at once when a child starts while
    the robot drives). ``shares`` False (a core to spare): never held."""

    def __init__(self, cores: Callable[[], float], clock: Callable[[], float] = time.monotonic) -> None:
        self.cores = cores  # asked when a child starts: a process may be moved into a cgroup
        self.shares = False  # the console has no core to spare for the child now running
        self.clock = clock
        self.holds = 0  # times the child was stopped (tests and the bench read it)
        self._lock = threading.Lock()
        self._pid: int | None = None
        self._held = False
        self._driving = False
        self._still_since = float("-inf")
        self._pidfd: int | None = None  # the child's, so a reused pid is never signalled
        self._held_s = 0.0  # the time the children were held (monotonic seconds)
        self._held_since: float | None = None

    @property
    def paused(self) -> bool:
        return self._held

    def held_s(self) -> float:
        """How long the children were held so far (the child's time limit leaves it out)."""
        with self._lock:
            since = self._held_since
            return self._held_s + (time.monotonic() - since if since is not None else 0.0)

    def child(self, pid: int | None) -> None:
        """The child now running, just started (None: it ended, or was killed)."""
        with self._lock:
            self._release()
            if pid is None:
                return
            self._pid = pid
            with contextlib.suppress(AttributeError, OSError):  # Linux 5.3+; else the pid itself
                self._pidfd = os.pidfd_open(pid)
            self.shares = self.cores() < SPARE_CORES
            if self.shares and self._driving:
                self._signal(signal.SIGSTOP)

    def driving(self, moving: bool) -> None:
        """The robot is (or is not) being driven, as of the control tick that just ran."""
        now = self.clock()
        with self._lock:
            if moving:
                self._driving = True
                if self.shares and not self._held:
                    self._signal(signal.SIGSTOP)
                return
            if self._driving:
                self._driving = False
                self._still_since = now
            if self._held and now - self._still_since >= RESUME_S:
                self._signal(signal.SIGCONT)

    def _signal(self, sig: signal.Signals) -> None:
        if self._pid is None:
            return
        try:
            if self._pidfd is not None:
                signal.pidfd_send_signal(self._pidfd, sig)
            else:
                os.kill(self._pid, sig)
        except OSError:  # gone already: the wait for it sees that
            self._release()
            return
        if sig == signal.SIGSTOP:
            self._held, self._held_since = True, time.monotonic()
            self.holds += 1
        else:
            self._count_held()

    def _count_held(self) -> None:
        if self._held_since is not None:
            self._held_s += time.monotonic() - self._held_since
        self._held, self._held_since = False, None

    def _release(self) -> None:
        """The current child is no longer ours to signal."""
        self._pid = None
        self._count_held()
        if self._pidfd is not None:
            with contextlib.suppress(OSError):
                os.close(self._pidfd)
            self._pidfd = None


_PR_SET_PDEATHSIG = 1
_prctl: Callable[..., int] | None
try:
    _prctl = ctypes.CDLL(None, use_errno=True).prctl
except (AttributeError, OSError):  # not Linux
    _prctl = None


def _child_setup(console: int) -> None:
    """In the child, before it runs: a lower priority, and death with the ``console`` (its pid; one
    that died between the fork and the ``prctl`` is seen at once)."""
    with contextlib.suppress(OSError):
        os.nice(NICE)
    if _prctl is not None:
        _prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
        if os.getppid() != console:
            os._exit(1)


async def sweep_curve(
    mission: str, speed: float, turn: float, cache: bool = True, pause: SweepPause | None = None
) -> LinkCurve:
    """Every controller on ``mission`` at each of ``SWEEP_LATENCIES_MS``; CurveError says why not. From
    the cache when this setting was swept before (``cache``), else from the child, which is killed if
    this is cancelled (the screen closed, the app quit) and held by ``pause`` while the robot drives."""
    path = await asyncio.to_thread(cache_path, mission, speed, turn) if cache else None
    if path is not None:
        curve = await asyncio.to_thread(_cached, path, mission)
        if curve is not None:
            return curve
    proc = await asyncio.create_subprocess_exec(
        *command(mission, speed, turn),
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
        stdin=asyncio.subprocess.DEVNULL,
        preexec_fn=functools.partial(_child_setup, os.getpid()),
    )
    try:
        if pause is not None:
            pause.child(proc.pid)
        out, err = await _answer(proc, pause)
    except (asyncio.CancelledError, TimeoutError):
        with contextlib.suppress(ProcessLookupError):
            proc.kill()  # a stopped process dies of SIGKILL too
        with contextlib.suppress(Exception):
            await asyncio.shield(proc.wait())
        raise
    finally:
        if pause is not None:
            pause.child(None)
    if proc.returncode != 0:
        line = err.decode(errors="replace").strip().splitlines()
        raise CurveError(line[-1] if line else f"compare exited with {proc.returncode}")
    try:
        body = json.loads(out)
    except ValueError as exc:
        raise CurveError(f"compare answered no JSON: {exc}") from None
    curve = curve_of(body, mission)
    if path is not None:
        await asyncio.to_thread(_keep, path, out)
    return curve


async def _answer(proc: asyncio.subprocess.Process, pause: SweepPause | None) -> tuple[bytes, bytes]:
    """The child's output; TimeoutError after ``TIMEOUT_S`` of its running (not paused) time."""
    answer = asyncio.ensure_future(proc.communicate())
    started = time.monotonic()
    held = pause.held_s() if pause is not None else 0.0
    try:
        while True:
            done, _ = await asyncio.wait({answer}, timeout=POLL_S)
            if done:
                return answer.result()
            ran = time.monotonic() - started - ((pause.held_s() - held) if pause is not None else 0.0)
            if ran > TIMEOUT_S:
                raise TimeoutError
    finally:
        answer.cancel()
