"""What the console asks the user, and what it tells them about exports and recordings: the goal prompt,
the clear confirmation, the export chooser and an export's notices, opening a recording. The console
owns one :class:`Dialogs` (``console.dialogs``); the screens' keys and the palette call it, and no
screen imports a dialog."""

from __future__ import annotations

import logging
from functools import partial
from pathlib import Path
from typing import Any

from textual.app import App

from arbiter_core.controllers import goal_driver

from ..analytics.exports import ExportFormatError
from ..analytics.files import Collected
from ..session.recording import open_recording
from ..session.robot import ExportResult
from .messages import GoalPicked, RecordingFailed, RecordingOpened, unexpected
from .screens.base import Console
from .screens.confirm import ConfirmClear
from .screens.export import ExportChooser
from .screens.goal import GoalPrompt
from .screens.open_file import OpenRecording

log = logging.getLogger(__name__)


class Dialogs:
    def __init__(self, app: App[Any], console: Console) -> None:
        self.app = app
        self.console = console

    def ask_goal(self) -> None:
        """``t``: type a go-to-goal target; the app drives there (``GoalPicked``)."""
        session = self.console.session

        def where() -> tuple[float, float]:  # the link's pose now (the prompt says it live)
            pose = session.link.telemetry.snapshot()[0]
            return pose.x, pose.y

        def chosen(goal: tuple[float, float] | None) -> None:
            if goal is not None:
                self.app.post_message(GoalPicked(*goal))

        self.app.push_screen(GoalPrompt(where, goal_driver(session.loop.algorithm)), chosen)

    def ask_clear(self) -> None:
        """Clearing the collected samples asks first (nothing else in the console destroys data)."""

        def done(confirmed: bool | None) -> None:
            if confirmed:
                self.app.notify(f"cleared {self.console.session.clear()} samples", timeout=3)
                self.console.refresh_frame(force=True)

        self.app.push_screen(ConfirmClear(len(self.console.session.store)), done)

    def ask_export(self) -> None:
        """The export chooser, then the export."""

        data = self.console.session.collected()  # what it says it exports is what the file gets

        def chosen(formats: tuple[str, ...] | None) -> None:
            if formats:
                self.export(*formats, data=data)

        self.app.push_screen(ExportChooser(len(data.points)), chosen)
        self.console.refresh_frame(force=True)  # the status line's count, taken at the same moment

    def export(self, *formats: str, data: Collected | None = None) -> list[ExportResult]:
        """Write the collected data (``data``: as the chooser took it) in each format, all under one
        file stem, and say what became of it: the whole path written, nothing to write, or the failure
        (the collected data is kept)."""
        results = self.console.session.export(*formats, data=data)
        for r in results:
            if r.path is not None:
                where = Path(r.path).resolve()  # the whole path: no guessing where
                self.app.notify(f"wrote {where} ({r.points} points)", timeout=4, markup=False)
            elif r.nothing:
                self.app.notify(r.error or "", severity="warning", timeout=6)
            else:
                text = f"EXPORT FAILED ({r.fmt}): {r.error} — collected data kept"
                self.app.notify(text, severity="error", timeout=8, markup=False)
        return results

    def open_recording(self) -> None:
        """A recording on the analytics screen: the path asked for, the file read and graded on a
        worker's thread (a long bag takes seconds); ``RecordingOpened`` or ``RecordingFailed`` then."""

        def chosen(path: Path | None) -> None:
            if path is not None:
                self.app.notify(f"reading {path}…", timeout=3, markup=False)
                load = partial(self._load, path)
                self.app.run_worker(load, thread=True, group="recording", exclusive=True, exit_on_error=False)

        self.app.push_screen(OpenRecording(), chosen)

    def _load(self, path: Path) -> None:
        try:
            view = open_recording(path)
        except (ExportFormatError, OSError, ValueError) as exc:
            self.app.post_message(RecordingFailed(str(path), str(exc) or type(exc).__name__))
            return
        except MemoryError:
            self.app.post_message(RecordingFailed(str(path), "out of memory reading it"))
            return
        except Exception as exc:  # a fault of ours: said as well (the live session stays), and logged
            log.exception("opening %s failed", path)
            self.app.post_message(RecordingFailed(str(path), unexpected(exc)))
            return
        self.app.post_message(RecordingOpened(view))

    def open_path(self, path: Path) -> None:
        """A recording at a known path (the journal a start found) on the analytics screen, read on a
        worker's thread as :meth:`open_recording` reads it."""
        self.app.notify(f"reading {path}…", timeout=3, markup=False)
        load = partial(self._load, path)
        self.app.run_worker(load, thread=True, group="recording", exclusive=True, exit_on_error=False)

    def live_session(self) -> None:
        """The live session again, in place of a recording."""
        self.app.post_message(RecordingOpened(None))
