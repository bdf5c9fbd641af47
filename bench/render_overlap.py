#!/usr/bin/env python
"""Which late commands a screen update was painting over: bench/pi.py's records beside the render probe.

For each screen measured: the commands that left late (their stamp more than ``--late-ms`` after the
previous one's plus a period), and for each the screen updates (bench/renderprobe) running at the time
it was due; then how long the updates took (wall and CPU) and how long after a control tick they began.
Usage in bench/renderprobe/sitecustomize.py.
"""

from __future__ import annotations

import argparse
import itertools
import json
from collections import defaultdict
from pathlib import Path

from _common import pct

PERIOD_S = 0.1  # the control loop's, 10 Hz


def read_probe(paths: list[Path]) -> dict[str, list[tuple[float, float, float]]]:
    """(start epoch s, wall s, cpu s) of each ``render`` and ``sample`` line."""
    out: dict[str, list[tuple[float, float, float]]] = defaultdict(list)
    for path in paths:
        for line in path.read_text().splitlines():
            kind, t0, wall, cpu = line.split()
            out[kind].append((float(t0), float(wall) / 1000.0, float(cpu) / 1000.0))
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("records", type=Path, help="bench/pi.py --records output (JSON lines)")
    p.add_argument("probe", type=Path, nargs="+", help="/tmp/arbiter-render-PID.log of the console")
    p.add_argument("--late-ms", type=float, default=5.0, help="a command this much late counts as late")
    a = p.parse_args()
    renders = read_probe(a.probe)["render"]
    by_screen: dict[str, list[float]] = defaultdict(list)
    for line in a.records.read_text().splitlines():
        r = json.loads(line)
        by_screen[f"{r['size']} {r['screen']}"].append(r["timestamp"] - r["latency_ms"] / 1000.0)
    for screen, stamps in by_screen.items():
        stamps.sort()
        inside = [r for r in renders if stamps[0] <= r[0] <= stamps[-1]]
        late = over = 0
        for before, stamp in itertools.pairwise(stamps):
            due = before + PERIOD_S
            if (stamp - due) * 1000.0 <= a.late_ms:
                continue
            late += 1
            running = [r for r in inside if r[0] <= due <= r[0] + r[1]]
            over += bool(running)
            where = ", ".join(f"began {(due - r[0]) * 1000:.0f} ms before, {r[1] * 1000:.0f} ms wall / "
                              f"{r[2] * 1000:.1f} ms CPU" for r in running)  # fmt: skip
            print(f"  {screen}: left {(stamp - due) * 1000:.1f} ms late; updates running: {where or 'none'}")
        # when each update began, after the latest command before it
        after_tick = []
        for t0, _wall, _cpu in inside:
            last = max((s for s in stamps if s <= t0), default=None)
            if last is not None:
                after_tick.append((t0 - last) * 1000.0)
        walls = [r[1] * 1000.0 for r in inside]
        cpus = [r[2] * 1000.0 for r in inside]
        print(
            f"{screen}: {len(stamps)} commands, {late} over {a.late_ms:g} ms late, {over} of them while an "
            f"update ran; {len(inside)} updates, wall ms p50 {pct(walls, 0.5)} max "
            f"{max(walls, default=0):.0f}, CPU ms p50 {pct(cpus, 0.5)} max {max(cpus, default=0):.1f}, "
            f"began ms after a command p50 {pct(after_tick, 0.5)}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
