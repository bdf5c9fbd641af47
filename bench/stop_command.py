#!/usr/bin/env python
"""The command that stops the robot at a mission's end, against the mission's other commands.

Starts the console as a person does (``arbiter-tui`` in a tmux terminal of 100x30, embedded backend),
drives ``--missions`` square missions with go_to_goal at 1 m/s (``g`` again as soon as one ends), and
reads the tracker's records: the one-way latency (tracker receive minus the console's stamp; one host,
one clock) of each mission's stop command (the zero after its driving commands) beside the p50/p99 of
the driving commands. A headless console (Textual's ``run_test``) does not show the effect: it needs a
real terminal drawing what the mission's end paints. Needs tmux. Last line: one JSON object.

    python bench/stop_command.py --missions 6 --runs 2

The stop once arrived 10-20x slower than the others on a loaded machine: the "finished" toast was
painted (and the terminal drew it) at the very moment the stop went out, taking the CPU the backend
needed to take the command. The console's own part (stamp to socket write) stays ~0.05 ms either way.
"""

from __future__ import annotations

import argparse
import itertools
import re
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

import httpx
from _common import emit

SESSION = "arbiter-stop-bench"
ROOT = Path(__file__).resolve().parent.parent


def _tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, check=False).stdout


def _screen() -> str:
    return _tmux("capture-pane", "-p", "-t", SESSION)


def _wait(predicate, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.2)
    return predicate()


def one_run(missions: int) -> tuple[list[float], list[float]]:
    """(stop command latencies, driving command latencies) of one console session, in ms."""
    _tmux("kill-session", "-t", SESSION)
    console = f"{sys.executable} -m arbiter_tui.cli --speed 1.0 --turn 2.0"
    _tmux("new-session", "-d", "-s", SESSION, "-x", "100", "-y", "30", "-c", str(ROOT), console)
    try:
        assert _wait(lambda: "CONNECTED" in _screen(), 30), _screen()
        found = re.search(r"embedded (\d+)/(\d+)", _screen())
        assert found, _screen()
        api = f"http://127.0.0.1:{found.group(2)}"
        _tmux("send-keys", "-t", SESSION, "a")
        for _ in range(missions):
            _tmux("send-keys", "-t", SESSION, "g")
            assert _wait(lambda: "(driving)" in _screen(), 5), _screen()
            assert _wait(lambda: "(driving)" not in _screen(), 60), "the mission did not end"
        time.sleep(1.0)  # the last stop's record
        records = httpx.get(f"{api}/api/latency?limit=1000", timeout=10).json()["records"]
    finally:
        _tmux("send-keys", "-t", SESSION, "C-q")
        time.sleep(1.0)
        _tmux("kill-session", "-t", SESSION)
    records.sort(key=lambda r: r["seq"])
    stops, driving = [], []
    for before, r in itertools.pairwise(records):
        moving = before["linear_x"] != 0.0 or before["angular_z"] != 0.0
        if r["linear_x"] == 0.0 and r["angular_z"] == 0.0 and moving:
            stops.append(r["latency_ms"])
        elif r["linear_x"] != 0.0 or r["angular_z"] != 0.0:
            driving.append(r["latency_ms"])
    return stops, driving


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--missions", type=int, default=6, help="per run (the tracker keeps 1000 records)")
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--slow-ms", type=float, default=1.0, help="a stop slower than this counts as slow")
    args = parser.parse_args(argv)
    if shutil.which("tmux") is None:
        print("needs tmux (apt-get install tmux)", file=sys.stderr)
        return 2
    stops: list[float] = []
    driving: list[float] = []
    for _ in range(args.runs):
        s, d = one_run(args.missions)
        stops += s
        driving += d
    driving.sort()
    p50 = statistics.median(driving)
    p99 = driving[int(len(driving) * 0.99)]
    slow = sum(s > args.slow_ms for s in stops)
    print(f"driving commands: p50 {p50:.3f} ms, p99 {p99:.3f} ms ({len(driving)})")
    shown = ", ".join(f"{s:.3f}" for s in stops)
    print(f"stop commands: {shown} ms; {slow} of {len(stops)} over {args.slow_ms} ms")
    emit(
        {
            "bench": "stop_command",
            "runs": args.runs,
            "missions": len(stops),
            "driving_p50_ms": round(p50, 4),
            "driving_p99_ms": round(p99, 4),
            "stop_ms": [round(s, 4) for s in stops],
            "stop_median_ms": round(statistics.median(stops), 4) if stops else None,
            "slow_stops": slow,
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
