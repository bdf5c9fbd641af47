"""Everything that happens in the console, as past-tense Textual messages (one place to read them all).

Data that changes continuously (pose, link state, stats) reaches widgets as one frozen frame
(``session/frames.py``) sampled at the UI rate. Messages are for events: something
finished, failed or was decided.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from textual.message import Message

from ..control.stop import StopReport
from ..latency.tracker_client import TrackerClient
from ..link.base import Link
from ..session.frames import FrameClock
from ..session.heartbeat import OperatorBack, OperatorUnknown
from ..session.journal import Found
from ..session.robot import JournalSaid, MissionFinished, StopDone
from ..session.views import AnalyticsView

Severity = Literal["information", "warning", "error"]


@dataclass(frozen=True)
class Notice:
    """What the console tells the user about an event: a notification that expires."""

    text: str
    severity: Severity = "information"
    timeout: float = 4.0
    after_s: float = 0.0  # shown this long after the event (0: at once)


def unexpected(exc: BaseException) -> str:
    """A failure no worker expected, in the one line a worker says it in: its kind and what it says (the
    log has its traceback)."""
    return f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__


class Said(Message):
    """An event the user is told about; the app shows each one's :meth:`notice` (None: nothing to say)."""

    def notice(self) -> Notice | None:
        return None


class BackendStarted(Message):
    """The link (and the tracker poller, when there is one) are ready: the console can drive."""

    def __init__(self, link: Link, tracker: TrackerClient | None, cleanup: Callable[[], None]) -> None:
        super().__init__()
        self.link = link
        self.tracker = tracker
        self.cleanup = cleanup


class BackendFailed(Message):
    """Starting the embedded backend or the link failed; the console stays up and says why."""

    def __init__(self, error: str) -> None:
        super().__init__()
        self.error = error


NOTICE_AFTER_STOP_S = 0.1  # a run's end is told once its stop command has reached the robot


class RunFinished(Said):
    """An autonomous mission run reached its last waypoint."""

    def __init__(self, algorithm: str, mission: str) -> None:
        super().__init__()
        self.algorithm = algorithm
        self.mission = mission

    def notice(self) -> Notice:
        # told once the stop command the run's end sent is through: painted at once (and the terminal
        # drawing it), it took the CPU the backend needed to take that command, which then arrived 10-20x
        # slower than the others (bench/stop_command.py --tmux)
        text = f"{self.algorithm} finished the {self.mission} mission"
        return Notice(text, after_s=NOTICE_AFTER_STOP_S)


class GoalPicked(Message):
    """The user chose a go-to-goal target (a click on the map or a typed ``x y``), in metres, odom frame."""

    def __init__(self, x: float, y: float) -> None:
        super().__init__()
        self.x = x
        self.y = y


class LinkSweepFailed(Said):
    """The analytics screen's latency sweep (``arbiter-tui compare`` in a child process) failed."""

    def __init__(self, error: str) -> None:
        super().__init__()
        self.error = error

    def notice(self) -> Notice:
        return Notice(f"latency sweep failed: {self.error}", "warning", 8)


class FrameDue(Message):
    """A control tick just ended and a frame is due (``session.frames.FrameClock``): painted now, it is
    done before the next command."""

    def __init__(self, clock: FrameClock) -> None:
        super().__init__()
        self.clock = clock


class StopReported(Said):
    """A stop's part beyond the console's own commands ended (``session/remote_stop.py``): what it did."""

    def __init__(self, report: StopReport) -> None:
        super().__init__()
        self.report = report

    def notice(self) -> Notice | None:
        r = self.report
        return Notice(r.text(), "warning" if r.unsure else "information", 10) if r.worth_saying() else None


class RecordingOpened(Said):
    """A recording or an export was read and graded (``session/recording.py``): the analytics show it
    (None: the user asked for the live session again)."""

    def __init__(self, view: AnalyticsView | None) -> None:
        super().__init__()
        self.view = view

    def notice(self) -> Notice | None:
        if self.view is None:
            return None
        return Notice(f"showing {self.view.source}: escape on screen 2 for the live session", timeout=5)


class RecordingFailed(Said):
    """A file the user asked to open could not be read: one line saying why."""

    def __init__(self, path: str, error: str) -> None:
        super().__init__()
        self.path = path
        self.error = error

    def notice(self) -> Notice:
        return Notice(f"cannot open {self.path}: {self.error}", "error", 10)


class JournalFound(Said):
    """The start found the journal of a session that did not end cleanly (``session/journal.py``)."""

    def __init__(self, found: Found) -> None:
        super().__init__()
        self.found = found

    def notice(self) -> Notice:
        return Notice(self.found.text(), "warning", 30)


class JournalStopped(Said):
    """The journal could not go on: a full disk, an unwritable directory, its bound reached."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.text = text

    def notice(self) -> Notice:
        return Notice(self.text, "warning", 10)


class OperatorSaid(Said):
    """The person's terminal answers again after a silence (what held meanwhile), or the console cannot
    tell whether it hears it (``session/heartbeat.py``)."""

    def __init__(self, event: OperatorBack | OperatorUnknown) -> None:
        super().__init__()
        self.event = event

    def notice(self) -> Notice | None:
        e = self.event
        if isinstance(e, OperatorUnknown):
            return Notice(e.text, "warning", 12)
        return Notice(e.text(), "warning" if e.held else "information", 30 if e.held else 6)


def session_said(event: object) -> Said | None:
    """The message for an event of the robot session (told from its threads), None for none."""
    if isinstance(event, MissionFinished):
        return RunFinished(event.algorithm, event.mission)
    if isinstance(event, StopDone):
        return StopReported(event.report)
    if isinstance(event, Found):
        return JournalFound(event)
    if isinstance(event, JournalSaid):
        return JournalStopped(event.text)
    if isinstance(event, (OperatorBack, OperatorUnknown)):
        return OperatorSaid(event)
    return None
