"""A terminal program as a person sees it: tmux runs it, ``capture-pane`` reads its screen."""

import re
import subprocess

from .waits import wait_for

TOAST_BAR = "▌"  # the left edge of a Textual notification
_BOX = re.compile(r"[┃│┛┓┗┏┣┫╯╮╰╭]")


def new_session(name: str, cols: int, rows: int, command: str) -> None:
    """A detached session ``name`` of ``cols`` x ``rows`` running ``command``. tmux's server exits when
    its last session closes; a ``new-session`` that reaches it while it exits fails (test_journal once
    found no session, no console started, right after the test before it closed its last one): made
    again, a few times, until tmux says it was made."""
    args = ["tmux", "new-session", "-d", "-s", name, "-x", str(cols), "-y", str(rows), command]
    errors: list[str] = []

    def made() -> bool:
        done = subprocess.run(args, capture_output=True, text=True, timeout=10)
        if done.returncode != 0:
            errors.append(done.stderr.strip())
            return False
        # (and it is there: a server that was exiting may take the session with it)
        there = subprocess.run(["tmux", "has-session", "-t", name], capture_output=True, timeout=10)
        return there.returncode == 0

    if not wait_for(made, timeout=5, interval=0.2):
        raise AssertionError(f"tmux could not make session {name}: {errors}")


def toast_text(screen: str) -> str:
    """The words of the notifications on ``screen`` as one line: a notification wraps its text inside
    its box, and where the wrap falls moves with a time or a path in it."""
    parts = []
    for line in screen.splitlines():
        if TOAST_BAR in line:
            parts.append(_BOX.split(line.split(TOAST_BAR, 1)[1], 1)[0].strip())
    return " ".join(p for p in parts if p)


def on_screen(text: str, screen: str) -> bool:
    """``text`` on ``screen``, or in its notifications read as one line."""
    return text in screen or text in toast_text(screen)


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10).stdout


def screen_until(session: str, *texts: str, timeout: float = 10.0, join: bool = False) -> str:
    """The screen once every one of ``texts`` is on it (``join``: wrapped lines read as one); an
    AssertionError showing the screen when they are not within ``timeout``."""
    shown = [""]

    def showing() -> bool:
        shown[0] = tmux("capture-pane", "-p", *(["-J"] if join else []), "-t", session)
        return all(on_screen(t, shown[0]) for t in texts)

    if wait_for(showing, timeout, interval=0.1):
        return shown[0]
    raise AssertionError(f"{texts!r} not on screen:\n{shown[0]}")
