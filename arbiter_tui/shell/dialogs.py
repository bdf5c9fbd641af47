"""What the console asks the user, and what it tells them about exports: the goal prompt, the clear
confirmation, and an export's notices. Called by the screens' keys and by the palette alike."""

from __future__ import annotations

from pathlib import Path

from textual.app import App

from ..session.robot import ExportResult
from .messages import GoalPicked
from .screens.base import Console


def ask_goal(app: App[object], console: Console) -> None:
    """``t``: type a go-to-goal target; the app drives there (``GoalPicked``)."""
    from arbiter_core.controllers import goal_driver

    from .screens.goal import GoalPrompt

    session = console.session
    pose = session.link.telemetry.snapshot()[0]

    def chosen(goal: tuple[float, float] | None) -> None:
        if goal is not None:
            app.post_message(GoalPicked(*goal))

    app.push_screen(GoalPrompt((pose.x, pose.y), goal_driver(session.loop.algorithm)), chosen)


def ask_clear(app: App[object], console: Console) -> None:
    """Clearing the collected samples asks first (nothing else in the console destroys data)."""
    from .screens.confirm import ConfirmClear

    def done(confirmed: bool | None) -> None:
        if confirmed:
            app.notify(f"cleared {console.session.clear()} samples", timeout=3)
            console.refresh_frame(force=True)

    app.push_screen(ConfirmClear(len(console.session.store)), done)


def export(app: App[object], console: Console, *formats: str) -> list[ExportResult]:
    """Write the collected data in each format, all under one file stem, and say what became of it: the
    whole path written, nothing to write, or the failure (the collected data is kept)."""
    results = console.session.export(*formats)
    for r in results:
        if r.path is not None:
            where = Path(r.path).resolve()  # the whole path: no guessing where
            app.notify(f"wrote {where} ({r.points} points)", timeout=4, markup=False)  # a path is no markup
        elif r.nothing:
            app.notify(r.error or "", severity="warning", timeout=6)
        else:
            text = f"EXPORT FAILED ({r.fmt}): {r.error} — collected data kept"
            app.notify(text, severity="error", timeout=8, markup=False)
    return results


def open_recording(app: App[object]) -> None:
    """Open a recording on the analytics screen (``recording.py``)."""
    from . import recording

    recording.ask(app)


def live_again(app: App[object]) -> None:
    from . import recording

    recording.close(app)
