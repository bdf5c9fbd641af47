"""The console's CPU per screen, in process (Textual's headless driver: everything but the terminal
write), for an A/B of two checkouts in the same run on a noisy machine.

The app runs live on the client-side simulator with a go_to_goal mission driving; after a 3 s warm-up
the process's CPU over ``--seconds`` is taken, per screen, alternating the checkouts ``--repeat``
times; medians are printed. ``--against DIR`` is another checkout's root (e.g. a ``git worktree`` of
an older commit), imported through PYTHONPATH.

    python bench/screen_cpu.py --against /tmp/old --size 100x30 --screens control,analytics
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CHILD = """
import asyncio, sys, time
from arbiter_tui.shell.app import make_app
from arbiter_tui.link.sim import SimLink
from arbiter_tui.session.settings import Settings

W, H, KEY, SECONDS = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], float(sys.argv[4])

async def main():
    app = make_app(Settings(mode="sim", live=True, handle_signals=False), SimLink())
    async with app.run_test(size=(W, H)) as pilot:
        await pilot.press("a", "g", KEY)
        await pilot.pause(3.0)
        c0, t0 = time.process_time(), time.monotonic()
        await pilot.pause(SECONDS)
        print(100.0 * (time.process_time() - c0) / (time.monotonic() - t0))

asyncio.run(main())
"""
KEYS = {"control": "1", "analytics": "2", "latency": "3"}


def once(pythonpath: Path, size: tuple[int, int], screen: str, seconds: float) -> float:
    env = {**os.environ, "PYTHONPATH": str(pythonpath)}
    args = [sys.executable, "-c", CHILD, str(size[0]), str(size[1]), KEYS[screen], str(seconds)]
    out = subprocess.run(args, env=env, capture_output=True, text=True, check=True, timeout=seconds + 60)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--against", type=Path, help="another checkout's root to compare with")
    p.add_argument("--size", default="100x30", help="terminal size, COLSxROWS")
    p.add_argument("--screens", default="control,analytics,latency", help="comma-separated")
    p.add_argument("--seconds", type=float, default=8.0, help="measured per run")
    p.add_argument("--repeat", type=int, default=3, help="runs of each, alternating; medians reported")
    a = p.parse_args()
    cols, rows = (int(v) for v in a.size.split("x"))
    sides = {"this": ROOT} | ({"against": a.against.resolve()} if a.against else {})
    result: dict = {"bench": "screen_cpu", "size": a.size, "seconds": a.seconds, "repeat": a.repeat}
    for screen in a.screens.split(","):
        runs: dict[str, list[float]] = {name: [] for name in sides}
        for _ in range(a.repeat):
            for name, path in sides.items():
                runs[name].append(once(path, (cols, rows), screen, a.seconds))
        result[screen] = {name: round(statistics.median(v), 2) for name, v in runs.items()}
        if a.against:
            result[screen]["ratio"] = round(result[screen]["this"] / result[screen]["against"], 2)
    print(json.dumps(result, separators=(",", ":")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
