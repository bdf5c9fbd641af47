#!/usr/bin/env python
"""The console's own cost in a real terminal, as ratios to a bare Textual app measured in the same run.

Both run in detached tmux sessions (100x30 by default): ``arbiter-tui`` in embedded mode and
``bench/bare_app.py`` (a status line, a Static and a Sparkline updated at 5 Hz, a Footer). For each:
the first frame (launch until its status line is on screen), then phases of ``--seconds`` each with
the same key stream:

* ``control_key_held``: ``i`` every 0.1 s (a held key's auto-repeat: teleop commands flowing,
  the robot moving, the control screen live);
* ``latency_screen``: the latency screen open while the tracker is polled (keys: none);
* ``topics_screen``: the topics screen open while ``/api/topics`` is polled (keys: none);
* ``analytics_collecting``: a go_to_goal mission driving (recording is on from the start), analytics
  screen open.

The bare app gets the same keys and durations. CPU is the app process's user+system time (/proc; the
embedded backend child excluded); output is every byte written to the terminal (tmux ``pipe-pane``).
Each app runs ``--repeat`` times, alternating; the figures are medians and the ratios are of the
medians. Last line: JSON with both apps' figures and the ratios.

    python bench/tui.py --seconds 10 --repeat 3
    python bench/tui.py --seconds 10 --repeat 3 --pythonpath /path/to/another/checkout
    python bench/tui.py --first-frame-only --repeat 5      # only the first frames
    python bench/tui.py --tui-args=--no-journal            # the console without its journal

The console's user data directory (its journal) is a temporary one: a run never writes a developer's.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path

from _common import compile_checkout, emit

TICK = os.sysconf("SC_CLK_TCK")
HERE = Path(__file__).resolve().parent


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10).stdout


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK  # utime + stime


def screen(session: str) -> str:
    return tmux("capture-pane", "-p", "-t", session)


def wait_for(session: str, text: str, timeout: float) -> float | None:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if text in screen(session):
            return time.monotonic() - t0
        time.sleep(0.01)
    return None


def phase(session: str, pid: int, out: Path, seconds: float, key: str | None) -> dict:
    c0, b0, t0 = cpu_seconds(pid), out.stat().st_size, time.monotonic()
    while time.monotonic() - t0 < seconds:
        if key:
            tmux("send-keys", "-t", session, key)
        time.sleep(0.1)
    dt = time.monotonic() - t0
    cpu = cpu_seconds(pid) - c0
    written = out.stat().st_size - b0
    return {"cpu_percent_of_core": round(100 * cpu / dt, 2), "kb_per_s": round(written / dt / 1000, 2)}


def run(cmd: str, first_marker: str, ready_marker: str, steps: list, size: tuple, tmp: Path) -> dict:
    """Launch ``cmd`` in tmux, time its first frame, then run ``steps``: (name, keys before, key held)."""
    session = f"arbiter-bench-{uuid.uuid4().hex[:8]}"
    out = tmp / f"{session}.bytes"
    out.touch()
    # from a folder with no package in it: ``python -m`` puts the working directory first on sys.path,
    # ahead of PYTHONPATH, so from a checkout it would measure that checkout instead of --pythonpath's
    tmux("new-session", "-d", "-s", session, "-x", str(size[0]), "-y", str(size[1]), "-c", str(tmp), cmd)
    result: dict = {}
    try:
        tmux("pipe-pane", "-t", session, "-o", f"cat >> {out}")
        first = wait_for(session, first_marker, 30)
        result["first_frame_s"] = None if first is None else round(first, 3)
        pid = int(tmux("display-message", "-p", "-t", session, "#{pane_pid}").strip())
        wait_for(session, ready_marker, 30)
        time.sleep(1.0)
        for name, before, held, seconds in steps:
            for key in before:
                tmux("send-keys", "-t", session, key)
                time.sleep(0.2)
            time.sleep(0.5)
            result[name] = phase(session, pid, out, seconds, held)
        tmux("send-keys", "-t", session, "C-q")
        time.sleep(1.0)
    finally:
        tmux("kill-session", "-t", session)
    return result


def median_of(runs: list[dict]) -> dict:
    """The median of each figure over the runs (same keys)."""
    out: dict = {}
    for key, value in runs[0].items():
        if isinstance(value, dict):
            out[key] = median_of([r[key] for r in runs])
        else:
            values = [r[key] for r in runs if r[key] is not None]
            out[key] = round(statistics.median(values), 3) if values else None
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=20.0, help="length of each phase")
    p.add_argument("--size", default="100x30", help="terminal size, COLSxROWS")
    p.add_argument("--repeat", type=int, default=3, help="runs of each app, alternating; medians reported")
    p.add_argument("--pythonpath", help="measure the code of another checkout (its root)")
    p.add_argument("--first-frame-only", action="store_true", help="time the first frames, no phases")
    p.add_argument("--tui-args", default="", help="more flags for arbiter-tui, e.g. --no-journal")
    a = p.parse_args()
    if shutil.which("tmux") is None:
        print("tui: tmux is not installed", file=sys.stderr)
        return 1
    compile_checkout(a.pythonpath)  # compiled, as an installed copy is
    size = tuple(int(n) for n in a.size.split("x"))
    tmp = Path(tempfile.mkdtemp())
    s = a.seconds
    exe = f"env XDG_DATA_HOME={tmp} {Path(sys.executable).with_name('arbiter-tui')}"
    if a.pythonpath:  # the same console, imported from another checkout
        exe = f"env XDG_DATA_HOME={tmp} PYTHONPATH={a.pythonpath} {sys.executable} -m arbiter_tui.cli"
    tui_cmd = f"{exe} --bridge-port 0 --api-port 0 --export-dir {tmp} --log-file {tmp / 'tui.log'}"
    tui_cmd += f" {a.tui_args}"
    steps = [
        ("control_key_held", [], "i", s),
        ("latency_screen", ["3"], None, s),
        ("topics_screen", ["4"], None, s),  # GET /api/topics at 2 Hz while shown
        ("analytics_collecting", ["1", "a", "g", "2"], None, s),  # recording is on from the start
    ]
    if a.first_frame_only:
        steps = []
    bare_cmd = f"{sys.executable} {HERE / 'bare_app.py'}"
    tui_runs, bare_runs = [], []
    for _ in range(a.repeat):  # alternating, so slow spells of a shared machine hit both alike
        # the status line's target is on screen from the first frame
        tui_runs.append(run(tui_cmd, "embedded", "CONNECTED", steps, size, tmp))
        bare_runs.append(run(bare_cmd, "bare ready", "bare ready", steps, size, tmp))
    tui, bare = median_of(tui_runs), median_of(bare_runs)
    ratios: dict = {}
    for name in [step[0] for step in steps]:
        t, b = tui[name], bare[name]
        cpu_t, cpu_b = t["cpu_percent_of_core"], b["cpu_percent_of_core"]
        ratios[name] = {
            "cpu": round(cpu_t / cpu_b, 2) if cpu_b else None,
            "output": round(t["kb_per_s"] / b["kb_per_s"], 2) if b["kb_per_s"] else None,
        }
    first = None
    if tui.get("first_frame_s") is not None and bare.get("first_frame_s") is not None:
        first = round(tui["first_frame_s"] - bare["first_frame_s"], 3)
    emit({"bench": "tui", "size": a.size, "seconds_per_phase": s, "repeat": a.repeat, "tui_args": a.tui_args,
          "arbiter_tui": tui,
          "bare_textual": bare,
          "ratios": ratios, "first_frame_minus_bare_s": first})  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
