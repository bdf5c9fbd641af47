#!/usr/bin/env python
"""The TUI's own cost in a real terminal (tmux, 100x30, embedded mode): CPU and terminal output per minute.

Starts ``arbiter-tui`` in a detached tmux session, times the first frame (launch
until the status line is on screen), then measures two phases of ``--seconds``
each: the control screen while a key is held (``i`` auto-repeating at 10 Hz:
teleop commands flowing, robot moving, data collected) and the latency screen
open while the tracker is polled. CPU is the TUI process's user+system time
(from /proc, the backend child excluded); output is every byte the TUI wrote to
the terminal (tmux ``pipe-pane``). Last line: JSON, figures per minute.

    python bench/tui.py --seconds 30
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path

from _common import emit

TICK = os.sysconf("SC_CLK_TCK")


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10).stdout


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK  # utime + stime


def tui_pid(session: str) -> int:
    shell = int(tmux("display-message", "-p", "-t", session, "#{pane_pid}").strip())
    # the pane runs the TUI directly (no shell in between)
    return shell


def phase(session: str, pid: int, out: Path, seconds: float, key: str | None) -> dict:
    c0, b0, t0 = cpu_seconds(pid), out.stat().st_size, time.monotonic()
    while time.monotonic() - t0 < seconds:
        if key:
            tmux("send-keys", "-t", session, key)
        time.sleep(0.1)
    dt = time.monotonic() - t0
    cpu = cpu_seconds(pid) - c0
    written = out.stat().st_size - b0
    return {
        "cpu_s_per_min": round(cpu / dt * 60, 2),
        "cpu_percent_of_core": round(100 * cpu / dt, 2),
        "bytes_per_min": round(written / dt * 60),
        "kb_per_s": round(written / dt / 1000, 2),
    }


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=30.0)
    a = p.parse_args()
    if shutil.which("tmux") is None:
        print("tui: tmux is not installed", file=sys.stderr)
        return 1
    exe = str(Path(sys.executable).with_name("arbiter-tui"))
    session = f"arbiter-bench-{uuid.uuid4().hex[:8]}"
    tmp = Path(tempfile.mkdtemp())
    out = tmp / "terminal.bytes"
    out.touch()
    cmd = f"{exe} --bridge-port 0 --api-port 0 --export-dir {tmp} --log-file {tmp / 'tui.log'}"
    t_launch = time.monotonic()
    tmux("new-session", "-d", "-s", session, "-x", "100", "-y", "30", cmd)
    try:
        tmux("pipe-pane", "-t", session, "-o", f"cat >> {out}")
        first = None
        while time.monotonic() - t_launch < 30:
            screen = tmux("capture-pane", "-p", "-t", session)
            if "CONNECT" in screen:
                first = time.monotonic() - t_launch
                break
            time.sleep(0.01)
        pid = tui_pid(session)
        deadline = time.monotonic() + 15
        while "CONNECTED" not in tmux("capture-pane", "-p", "-t", session) and time.monotonic() < deadline:
            time.sleep(0.1)
        control = phase(session, pid, out, a.seconds, "i")
        tmux("send-keys", "-t", session, "3")
        time.sleep(1.0)
        latency = phase(session, pid, out, a.seconds, None)
        tmux("send-keys", "-t", session, "C-q")
        time.sleep(1.0)
    finally:
        tmux("kill-session", "-t", session)
    emit({"bench": "tui", "size": "100x30", "seconds_per_phase": a.seconds,
          "first_frame_s": None if first is None else round(first, 3),
          "control_teleop": control, "latency_screen": latency})  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
