"""A terminal program as a person sees it: tmux runs it, ``capture-pane`` reads its screen."""

import subprocess

from .waits import wait_for


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10).stdout


def screen_until(session: str, *texts: str, timeout: float = 10.0, join: bool = False) -> str:
    """The screen once every one of ``texts`` is on it (``join``: wrapped lines read as one); an
    AssertionError showing the screen when they are not within ``timeout``."""
    shown = [""]

    def showing() -> bool:
        shown[0] = tmux("capture-pane", "-p", *(["-J"] if join else []), "-t", session)
        return all(t in shown[0] for t in texts)

    if wait_for(showing, timeout, interval=0.1):
        return shown[0]
    raise AssertionError(f"{texts!r} not on screen:\n{shown[0]}")
