"""The real `arbiter-tui` in a real terminal (tmux): type keys, read the screen as a person would."""

import shutil
import subprocess
import sys
import time
import uuid
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10).stdout


def screen_until(session: str, text: str, timeout: float = 10.0) -> str:
    deadline = time.monotonic() + timeout
    out = ""
    while time.monotonic() < deadline:
        out = tmux("capture-pane", "-p", "-t", session)
        if text in out:
            return out
        time.sleep(0.1)
    raise AssertionError(f"{text!r} not on screen:\n{out}")


@pytest.mark.parametrize("mode", [["--sim"], []], ids=["sim", "embedded"])
def test_drive_and_quit_in_a_real_terminal(tmp_path, mode):
    session = f"arbiter-{uuid.uuid4().hex[:8]}"
    exe = Path(sys.executable).with_name("arbiter-tui")
    done = tmp_path / "exit"
    args = " ".join([*mode, "--bridge-port", "0", "--api-port", "0", "--export-dir", str(tmp_path)])
    cmd = f"{exe} {args}; echo $? > {done}"
    tmux("new-session", "-d", "-s", session, "-x", "100", "-y", "30", cmd)
    try:
        screen_until(session, "SIMULATED" if mode else "CONNECTED")
        for _ in range(8):
            tmux("send-keys", "-t", session, "i")
            time.sleep(0.08)
        screen = screen_until(session, "(teleop)")
        assert "v +0.50 m/s" in screen
        screen_until(session, "(stopped)", timeout=5)  # let go: the robot stops by itself
        tmux("send-keys", "-t", session, "2")
        screen_until(session, "r start/stop")
        tmux("send-keys", "-t", session, "C-c")
        deadline = time.monotonic() + 10
        while not done.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert done.read_text().strip() == "0"
    finally:
        tmux("kill-session", "-t", session)
