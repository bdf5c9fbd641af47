"""The real `arbiter-tui` in a real terminal (tmux): type keys, read the screen as a person would."""

import shutil
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import pytest

from ..support.tmux import new_session, screen_until, tmux
from ..support.waits import wait_for

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")


def launch_tui(tmp_path: Path, args: str, linger: bool = False) -> tuple[str, Path]:
    """``arbiter-tui ARGS`` in a new 100x30 tmux session; its exit status goes to the returned file.
    ``linger`` keeps the pane open afterwards (to read the terminal's state, or the TUI's pid)."""
    session = f"arbiter-{uuid.uuid4().hex[:8]}"
    exe = Path(sys.executable).with_name("arbiter-tui")
    done = tmp_path / "exit"
    cmd = f"{exe} {args}; echo $? > {done}" + ("; sleep 30" if linger else "")
    new_session(session, 100, 30, cmd)
    return session, done


def exit_status(done: Path, timeout: float = 10.0) -> str:
    deadline = time.monotonic() + timeout
    while not done.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    return done.read_text().strip()


@pytest.mark.parametrize("mode", [["--sim"], []], ids=["sim", "embedded"])
def test_drive_and_quit_in_a_real_terminal(tmp_path, mode):
    args = " ".join([*mode, "--bridge-port", "0", "--api-port", "0", "--export-dir", str(tmp_path)])
    session, done = launch_tui(tmp_path, args)
    try:
        screen_until(session, "SIMULATED" if mode else "CONNECTED")
        for _ in range(8):
            tmux("send-keys", "-t", session, "i")
            time.sleep(0.08)
        screen = screen_until(session, "(teleop)")
        assert "v +0.50 m/s" in screen
        screen_until(session, "(stopped)", timeout=5)  # let go: the robot stops by itself
        tmux("send-keys", "-t", session, "2")
        screen_until(session, "r Rec v Runs ^s Export")
        tmux("send-keys", "-t", session, "C-c")
        assert exit_status(done) == "0"
    finally:
        tmux("kill-session", "-t", session)


def _tui_pid(session: str) -> int:
    shell = tmux("display-message", "-p", "-t", session, "#{pane_pid}").strip()
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        out = subprocess.run(["pgrep", "-P", shell], capture_output=True, text=True).stdout.split()
        if out:
            return int(out[0])
        time.sleep(0.1)
    raise AssertionError("arbiter-tui process not found")


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/status") as fh:
            return "State:\tZ" not in fh.read()
    except FileNotFoundError:
        return False


@pytest.mark.parametrize("how", ["sighup", "kill-session"])
def test_hangup_stops_the_robot_exits_and_restores_the_terminal(tmp_path, backend, how):
    """SIGHUP, as when the SSH session dies: a zero goes out, the process exits, the terminal is
    left as it was. kill-session is the harsher version: SIGHUP and the terminal gone at once."""
    from ..support.backend import get_json

    args = (
        f"--connect --rosbridge ws://127.0.0.1:{backend.bridge_port} --tracker {backend.api} "
        f"--key-timeout 2 --export-dir {tmp_path}"
    )
    session, done = launch_tui(tmp_path, args, linger=True)
    released = threading.Event()
    try:
        screen_until(session, "CONNECTED")
        pid = _tui_pid(session)
        # the key held as a terminal repeats it (30 Hz) until the hangup: a hold judged by its repeats
        # ends a fraction of a second after the last one, so a few presses then a wait could read a stop

        def hold() -> None:
            while not released.wait(1 / 30):
                tmux("send-keys", "-t", session, "i")

        holder = threading.Thread(target=hold, daemon=True)
        holder.start()
        screen_until(session, "(teleop)")
        latest = lambda: get_json(f"{backend.api}/api/latency")["records"][-1:]  # noqa: E731
        assert wait_for(lambda: [r["linear_x"] for r in latest()] == [0.5], 5)  # driving, the key held
        if how == "sighup":
            subprocess.run(["kill", "-HUP", str(pid)], check=True)
        else:
            tmux("kill-session", "-t", session)
        deadline = time.monotonic() + 5
        while _alive(pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not _alive(pid), "arbiter-tui still running after the hangup"
        released.set()
        holder.join(2)
        last = get_json(f"{backend.api}/api/latency")["records"][-1]
        assert (last["linear_x"], last["angular_z"]) == (0.0, 0.0)  # the best-effort zero went out
        if how == "sighup":
            assert exit_status(done, timeout=5) == "0"
            # the terminal is back to normal: main screen, cursor shown, no mouse reporting
            state = tmux(
                "display-message", "-p", "-t", session, "#{alternate_on} #{cursor_flag} #{mouse_any_flag}"
            )
            assert state.split() == ["0", "1", "0"], state
    finally:
        released.set()
        tmux("kill-session", "-t", session)


def test_a_crashed_embedded_backend_is_restarted_and_the_console_carries_on(tmp_path):
    args = f"--bridge-port 0 --api-port 0 --export-dir {tmp_path}"
    session, done = launch_tui(tmp_path, args, linger=True)
    try:
        screen_until(session, "CONNECTED")
        tui = _tui_pid(session)
        child = subprocess.run(["pgrep", "-P", str(tui)], capture_output=True, text=True).stdout.split()
        assert len(child) == 1
        subprocess.run(["kill", "-9", child[0]], check=True)  # the backend dies under the console
        screen_until(session, "DISCONNECTED", timeout=3)
        screen = screen_until(session, " CONNECTED", timeout=10)  # restarted on the same ports
        assert "DISCONNECTED" not in screen.splitlines()[0]
        new = subprocess.run(["pgrep", "-P", str(tui)], capture_output=True, text=True).stdout.split()
        assert len(new) == 1 and new != child
        for _ in range(6):
            tmux("send-keys", "-t", session, "i")
            time.sleep(0.08)
        screen_until(session, "(teleop)")
        tmux("send-keys", "-t", session, "C-c")
        assert exit_status(done) == "0"
        assert not _alive(int(new[0]))  # and the restarted backend went with it
    finally:
        tmux("kill-session", "-t", session)
