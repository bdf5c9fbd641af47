"""A recording opened from the analytics screen (``f``, or the palette): the path asked for, the file
read and graded on a worker's thread (a long bag takes seconds), the analytics then show it until the
live session is asked back (``escape`` on the analytics screen)."""

from __future__ import annotations

from functools import partial
from pathlib import Path

from textual.app import App

from ..analytics.exports import ExportFormatError
from ..session.recording import open_recording
from .messages import RecordingFailed, RecordingOpened


def ask(app: App[object]) -> None:
    """The path prompt; the file is read once it is chosen."""
    from .screens.open_file import OpenRecording

    def chosen(path: Path | None) -> None:
        if path is not None:
            app.notify(f"reading {path}…", timeout=3, markup=False)
            load = partial(_load, app, path)
            app.run_worker(load, thread=True, group="recording", exclusive=True, exit_on_error=False)

    app.push_screen(OpenRecording(), chosen)


def _load(app: App[object], path: Path) -> None:
    try:
        view = open_recording(path)
    except (ExportFormatError, OSError, ValueError) as exc:
        app.post_message(RecordingFailed(str(path), str(exc) or type(exc).__name__))
        return
    except MemoryError:
        app.post_message(RecordingFailed(str(path), "out of memory reading it"))
        return
    app.post_message(RecordingOpened(view))


def close(app: App[object]) -> None:
    """The live session again."""
    app.post_message(RecordingOpened(None))
