"""Everything that happens in the console, as past-tense Textual messages (one place to read them all).

Data that changes continuously (pose, link state, stats) reaches widgets as one frozen frame
(``session/frames.py``) sampled at the UI rate. Messages are for events: something
finished, failed or was decided.
"""

from __future__ import annotations

from collections.abc import Callable

from textual.message import Message

from ..control.stop import StopReport
from ..latency.tracker_client import TrackerClient
from ..link.base import Link
from ..session.frames import FrameClock
from ..session.views import AnalyticsView


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


class RunFinished(Message):
    """An autonomous mission run reached its last waypoint."""

    def __init__(self, algorithm: str, mission: str) -> None:
        super().__init__()
        self.algorithm = algorithm
        self.mission = mission


class GoalPicked(Message):
    """The user chose a go-to-goal target (a click on the map or a typed ``x y``), in metres, odom frame."""

    def __init__(self, x: float, y: float) -> None:
        super().__init__()
        self.x = x
        self.y = y


class LinkSweepFailed(Message):
    """The analytics screen's latency sweep (``arbiter-tui compare`` in a child process) failed."""

    def __init__(self, error: str) -> None:
        super().__init__()
        self.error = error


class FrameDue(Message):
    """A control tick just ended and a frame is due (``session.frames.FrameClock``): painted now, it is
    done before the next command."""

    def __init__(self, clock: FrameClock) -> None:
        super().__init__()
        self.clock = clock


class StopReported(Message):
    """A stop's part beyond the console's own commands ended (``session/remote_stop.py``): what it did."""

    def __init__(self, report: StopReport) -> None:
        super().__init__()
        self.report = report


class RecordingOpened(Message):
    """A recording or an export was read and graded (``session/recording.py``): the analytics show it
    (None: the user asked for the live session again)."""

    def __init__(self, view: AnalyticsView | None) -> None:
        super().__init__()
        self.view = view


class RecordingFailed(Message):
    """A file the user asked to open could not be read: one line saying why."""

    def __init__(self, path: str, error: str) -> None:
        super().__init__()
        self.path = path
        self.error = error
