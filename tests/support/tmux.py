"""A terminal program as a person sees it: tmux runs it, ``capture-pane`` reads its screen."""

import re
import subprocess

from .waits import wait_for

TOAST_BAR = "▌"  # the left edge of a Textual notification
_BOX = re.compile(r"[┃│┛┓┗┏┣┫╯╮╰╭]")


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
