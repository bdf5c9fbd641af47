"""The analytics screen's error-vs-latency curve: ``arbiter-tui compare`` in a child process.

A child process, not a thread: the sweep is pure Python, and in a thread it would hold the GIL the
console's control loop needs (the robot's commands would wait behind it). The child runs at a lower
priority (``nice``), so on a Raspberry Pi-class CPU the console keeps its core.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import sys

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


def _lower_priority() -> None:
    with contextlib.suppress(OSError):
        os.nice(NICE)


async def sweep_curve(mission: str, speed: float, turn: float) -> LinkCurve:
    """Every controller on ``mission`` at each of ``SWEEP_LATENCIES_MS``; CurveError says why not. The
    child is killed if this is cancelled (the screen closed, the app quit)."""
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
    return curve_of(body, mission)
