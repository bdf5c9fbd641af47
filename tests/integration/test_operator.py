"""An operator who cannot see cannot be driven past (docs/drive.md, "An operator who cannot see"): the
real ``arbiter-tui`` in a pseudo-terminal this test plays the person's terminal on (tests/support/
ptyterm.py), driving a real backend; what reaches the robot read from the backend's tracker."""

import glob
import os
import platform
import shutil
import sys
import time
import uuid

import httpx
import pytest

from arbiter_tui.session.heartbeat import PROBE_S
from tests.support.backend import start_backend
from tests.support.ptyterm import PtyTerminal
from tests.support.tmux import new_session, tmux
from tests.support.waits import wait_for

HOLD_BOUND_S = 1.5  # the bound: a mission holds within this of the answers stopping


@pytest.fixture(scope="module")
def backend():
    b = start_backend()
    yield b
    b.stop()


def records(backend) -> list[dict]:
    return httpx.get(f"{backend.api}/api/latency?limit=2000", timeout=5).json()["records"]


def moving(r: dict) -> bool:
    return (r["linear_x"], r["angular_z"]) != (0.0, 0.0)


def console(backend, tmp_path, *more: str) -> PtyTerminal:
    log = tmp_path / "console.log"
    url = f"ws://127.0.0.1:{backend.bridge_port}"
    return PtyTerminal(
        ["--rosbridge", url, "--tracker", backend.api, "--no-journal", "--log-file", str(log), *more]
    )


def start_mission(term: PtyTerminal, backend) -> None:
    """A controller selected (a) and its mission started (g, again while the link still comes up)."""
    assert wait_for(lambda: b"Drive" in term.output(), timeout=20), term.output()[-2000:]
    term.type("a")
    t0 = time.time()

    def started() -> bool:
        term.type("g")
        return wait_for(lambda: any(moving(r) and r["timestamp"] > t0 for r in records(backend)), 1.0)

    assert wait_for(started, timeout=20)


def test_a_mission_holds_while_the_terminal_does_not_answer_and_resumes_only_on_g(backend, tmp_path):
    term = console(backend, tmp_path)
    try:
        start_mission(term, backend)
        wait_for(lambda: term.answered >= 4, timeout=5)  # the console asks; the terminal answers
        # the link stalls: nothing read, nothing answered (the console's writes fill the pty, then block)
        t0 = time.time()
        term.reading = False
        term.answering = False
        time.sleep(HOLD_BOUND_S + 1.5)  # what goes to the robot meanwhile (proving nothing moves: a sleep)
        after = [r for r in records(backend) if r["timestamp"] > t0]
        late = [r for r in after if r["timestamp"] > t0 + HOLD_BOUND_S]
        assert after and not moving(after[-1]), after[-5:]
        assert not any(moving(r) for r in late), late  # held within the bound, zero on the wire
        held_at = next(r["timestamp"] for r in after if not moving(r)) - t0
        assert held_at <= HOLD_BOUND_S, held_at
        # the link returns: the screen says what held and how to resume; nothing moves until g
        mark = term.mark()
        term.reading = True
        term.answering = True
        assert wait_for(lambda: b"Press g to resume" in term.since(mark), timeout=10), term.since(mark)[
            -3000:
        ]
        seen = len(records(backend))
        time.sleep(1.0)  # (nothing moves without a key: a sleep)
        assert not any(moving(r) for r in records(backend)[seen:])
        term.type("g")
        assert wait_for(lambda: any(moving(r) for r in records(backend)[seen:]), timeout=10)
        log = (tmp_path / "console.log").read_text()
        assert "has not answered" in log and "square" in log and "answers again" in log
    finally:
        term.close()


def test_a_blocked_screen_never_stalls_a_mission_nor_the_deadman(backend, tmp_path):
    """With the heartbeat off: the console's terminal read by nobody (its writes block) while a mission
    drives: its commands keep flowing at the control rate; a key held then and let go stops the robot
    within its deadman, though no frame has been written since."""
    term = console(backend, tmp_path, "--operator-timeout", "0")
    try:
        start_mission(term, backend)
        t0 = time.time()
        term.reading = False
        time.sleep(3.0)  # commands go out meanwhile, or not
        flowing = [r for r in records(backend) if t0 + 0.5 < r["timestamp"] <= t0 + 3.0]
        assert len(flowing) >= 15 and all(moving(r) for r in flowing), flowing  # 10 Hz: ~25
        assert blocked_on_the_terminal(term.proc.pid), "the console's writes never blocked"
        for _ in range(30):  # i held for a second at a terminal's auto-repeat, then let go
            term.type("i")
            time.sleep(1 / 30)
        released = time.time()
        assert wait_for(lambda: not moving(records(backend)[-1]), timeout=5)
        last = records(backend)
        stop_at = next(r["timestamp"] for r in reversed(last) if moving(r))
        assert last[-1]["linear_x"] == 0.0 and stop_at - released < 0.8  # the deadman, screen or not
        assert any(r["linear_x"] == 0.5 and r["angular_z"] == 0.0 for r in last if r["timestamp"] > t0)
        assert blocked_on_the_terminal(term.proc.pid)
    finally:
        term.close()


def blocked_on_the_terminal(pid: int) -> bool:
    """Is one of the process's threads in a write(2) to its terminal (stdout or stderr: Textual writes
    to stderr) that has not returned: a full pty?"""
    write_nr = {"x86_64": 1, "aarch64": 64}[platform.machine()]
    for path in glob.glob(f"/proc/{pid}/task/*/syscall"):
        try:
            with open(path) as f:
                fields = f.read().split()
        except OSError:
            continue
        if len(fields) > 1 and fields[0] == str(write_nr) and int(fields[1], 16) in (1, 2):
            return True
    return False


# -- under tmux --------------------------------------------------------------------------------------------
needs_tmux = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")


def pane_shows(session: str, text: str, timeout: float = 10.0) -> bool:
    return wait_for(lambda: text in tmux("capture-pane", "-p", "-t", session), timeout=timeout, interval=0.1)


def tmux_console(tmp_path, *env_unset: str) -> str:
    """``arbiter-tui --sim`` in a new detached 100x30 tmux session (its environment less ``env_unset``)."""
    session = f"arbiter-{uuid.uuid4().hex[:8]}"
    unset = " ".join(f"-u {name}" for name in env_unset)
    cmd = (
        f"env {unset} PYTHONPATH={os.environ.get('PYTHONPATH', '')} {sys.executable} -m arbiter_tui.cli "
        f"--sim --no-journal --log-file {tmp_path / 'console.log'}"
    )
    new_session(session, 100, 30, cmd)
    return session


def attach(session: str) -> PtyTerminal:
    """A tmux client attached to ``session`` in a pty of its own: the person's terminal on the Pi."""
    return PtyTerminal(["attach", "-t", session], program=["tmux"])


@needs_tmux
def test_under_tmux_a_mission_holds_when_the_last_client_leaves(tmp_path):
    """tmux answers the cursor queries itself: the console asks tmux whether a client is attached. The
    client killed (an SSH session dropped, its tmux client gone) is nobody watching: the mission holds;
    the next client attached reads what held, and g resumes it."""
    session = tmux_console(tmp_path)
    client = attach(session)
    try:
        assert pane_shows(session, "Drive", 20)
        tmux("send-keys", "-t", session, "a")
        tmux("send-keys", "-t", session, "g")
        assert pane_shows(session, "(driving)")
        time.sleep(1.5)  # (attached: it drives on, polled once a second)
        assert "(driving)" in tmux("capture-pane", "-p", "-t", session)
        client.proc.kill()  # the client gone at once, as when sshd kills the session
        assert pane_shows(session, "(stopped)", 6), tmux("capture-pane", "-p", "-t", session)
        client.close()
        client = attach(session)
        assert pane_shows(session, "Press g to resume", 6), tmux("capture-pane", "-p", "-t", session)
        tmux("send-keys", "-t", session, "g")
        assert pane_shows(session, "(driving)")
    finally:
        client.close()
        tmux("kill-session", "-t", session)


@needs_tmux
def test_a_terminal_that_answers_the_cursor_queries_is_heard(tmp_path):
    """tmux playing the person's terminal (the console not told it runs under tmux): it answers the
    queries, so nothing is said at start and a mission drives on past the probe and the bound."""
    session = tmux_console(tmp_path, "TMUX", "TMUX_PANE")
    try:
        assert pane_shows(session, "Drive", 20)
        tmux("send-keys", "-t", session, "a")
        tmux("send-keys", "-t", session, "g")
        assert pane_shows(session, "(driving)")
        time.sleep(PROBE_S + 1.0)  # (past the probe: nothing said, nothing held)
        screen = tmux("capture-pane", "-p", "-t", session)
        assert "(driving)" in screen and "did not answer" not in screen, screen
        assert "did not answer" not in (tmp_path / "console.log").read_text()
    finally:
        tmux("kill-session", "-t", session)
