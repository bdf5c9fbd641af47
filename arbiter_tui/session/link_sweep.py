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
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import hashlib
import json
import os
import sys
import tempfile
from pathlib import Path

from ..analytics.linkcurve import SWEEP_LATENCIES_MS, CurveError, LinkCurve, curve_of

NICE = 10
TIMEOUT_S = 120.0
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


def _lower_priority() -> None:
    with contextlib.suppress(OSError):
        os.nice(NICE)


async def sweep_curve(mission: str, speed: float, turn: float, cache: bool = True) -> LinkCurve:
    """Every controller on ``mission`` at each of ``SWEEP_LATENCIES_MS``; CurveError says why not. From
    the cache when this setting was swept before (``cache``), else from the child, which is killed if
    this is cancelled (the screen closed, the app quit)."""
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
        preexec_fn=_lower_priority,
    )
    try:
        out, err = await asyncio.wait_for(proc.communicate(), TIMEOUT_S)
    except (asyncio.CancelledError, TimeoutError):
        with contextlib.suppress(ProcessLookupError):
            proc.kill()
        with contextlib.suppress(Exception):
            await asyncio.shield(proc.wait())
        raise
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
