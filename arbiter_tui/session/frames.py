"""What the console shows, as one frozen ``Frame`` a frame, from one pure sampler (no Textual).

The shell asks :class:`FrameSampler` for a frame at its UI rate (and at once after a user action) and
hands it to the screen in front; every widget picks its own typed field of it. The sampler is the one
place that decides how often each part changes: the robot panel and the map at the UI rate, the
analytics and latency panels at ``analytics_rate`` (a user action or a screen shown: at once), and the
status line's sample count at most every ``COUNT_PERIOD_S``. It reads the session's parts (link,
control loop, store; written on other threads, each behind its own lock) and what the pollers last
brought, and builds only what the screen shown will show; the rest keeps its last value, so an equal
part is the *same* object and a widget that picks it does no work.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, fields, replace
from typing import TypeVar

from ..analytics.linkcurve import FAILED, RUNNING, SWEEP_RETRY_S, LinkSweepView, measured_p95
from ..latency.autonomy import RobotSideView
from ..latency.topics_client import NO_BACKEND, TopicsState
from ..latency.tracker_client import TrackerAnswer, TrackerClient
from ..link.base import STARTING
from .cpu_share import cores_available
from .link_sweep import SweepPause
from .robot import RobotSession
from .settings import SIM, Settings
from .views import (
    AnalyticsView,
    LatencySnapshot,
    MapView,
    Observed,
    RobotView,
    StatusView,
    analytics_view,
    latency_snapshot,
    map_view,
    robot_view,
    status_view,
)

T = TypeVar("T")
COUNT_PERIOD_S = 1.0  # the status line's sample count follows at most this often

CONTROL, ANALYTICS, LATENCY, TOPICS = "control", "analytics", "latency", "topics"


@dataclass(frozen=True)
class Frame:
    """Everything the screens show, each part a frozen snapshot (``views.py``)."""

    status: StatusView = field(default_factory=StatusView)
    robot: RobotView = field(default_factory=RobotView)
    map: MapView = field(default_factory=MapView)
    analytics: AnalyticsView = field(default_factory=AnalyticsView)
    latency: LatencySnapshot = field(default_factory=LatencySnapshot)
    topics: TopicsState = field(default_factory=TopicsState)
    link_sweep: LinkSweepView = field(default_factory=LinkSweepView)


@dataclass(frozen=True)
class Shown:
    """What is on screen: the screen's name, and whether the control screen is the dashboard (which
    shows every part)."""

    screen: str = CONTROL
    dashboard: bool = False

    def shows(self, screen: str) -> bool:
        return self.screen == screen or self.dashboard


def _kept(old: T, new: T) -> T:
    """``old`` when ``new`` equals it: an unchanged part stays the same object, so a frame whose parts
    are all unchanged is the same frame."""
    return old if new == old else new


def astuple_shallow(frame: Frame) -> tuple[object, ...]:
    return tuple(getattr(frame, f.name) for f in fields(frame))


class FrameClock:
    """When the next frame is due, on the robot's clock: a frame starts just after a control tick, so
    that painting it has a whole control period before the next command is due.

    Under a CPU quota (a Pi-class core: 25 % of one) every thread of the console waits once the quota of
    a scheduling period is spent, and a frame that takes 5 ms of CPU takes 20 ms of wall time. A frame
    timer of its own drifts over the control ticks and, in a frame that covers one, delayed that command
    (bench/pi.py, the dashboard at 200x60). Started from the tick instead, the frame is over long before
    the next one. ``ticked`` runs on the session's thread after each control tick; ``drawn`` on the UI's
    once the frame is sampled (until then no other frame is asked for: a slow UI never piles them up).

    **The UI gives way to the robot.** Where painting a frame takes longer than a control period (a
    big terminal on a slow CPU), the command after it leaves late. ``ticked`` is told how late each
    command left (``late_s``); one later than ``LATE_S`` makes frames ``BACK_OFF`` times further apart
    (up to ``SLOWEST_S``), and every ``RECOVER_TICKS`` punctual ticks in a row bring them ``RECOVER``
    times closer again (down to the asked-for ``frame_s``). Where frames fit, nothing changes."""

    LATE_S = 0.015  # a command that left this much after its time was held up
    BACK_OFF = 1.5
    RECOVER = 0.9
    RECOVER_TICKS = 20  # two seconds of punctual commands at 10 Hz
    SLOWEST_S = 1.0

    def __init__(self, frame_s: float, tick_s: float, clock: Callable[[], float] = time.monotonic) -> None:
        self.asked_s = frame_s
        self.frame_s = frame_s  # the current distance between frames
        self.tick_s = tick_s
        self.clock = clock
        self.backed_off = 0  # times the frames were spread out (the bench reads it)
        self.asked = 0  # frames asked for
        self._due = float("-inf")
        self._pending = False
        self._punctual = 0
        self._echo_hold = float("-inf")

    def ticked(self, late_s: float = 0.0) -> bool:
        """A control tick just ended, its command ``late_s`` after its time: True when a frame is due
        now (and none is pending)."""
        self._adapt(late_s)
        now = self.clock()
        if self._pending or now < self._due:
            return False
        self._pending = True
        self._due = now + self.frame_s - self.tick_s / 2  # the tick nearest to one frame from now
        self.asked += 1
        return True

    def _adapt(self, late_s: float) -> None:
        if late_s > self.LATE_S:
            self._punctual = 0
            slower = min(self.SLOWEST_S, max(self.asked_s, self.frame_s * self.BACK_OFF))
            if slower > self.frame_s:
                self.frame_s = slower
                self.backed_off += 1
            return
        self._punctual += 1
        if self._punctual >= self.RECOVER_TICKS and self.frame_s > self.asked_s:
            self._punctual = 0
            self.frame_s = max(self.asked_s, self.frame_s * self.RECOVER)

    def drawn(self) -> None:
        self._pending = False

    ECHO_S = 0.3  # a key's echo on the person's screen within this (docs/benchmarks/ssh-link.md)

    def echoed(self, round_trip_s: float) -> None:
        """The person's terminal answered a query written behind the frames ``round_trip_s`` after it
        was written (``session/heartbeat.py``): the time a key's echo takes to reach the screen. Longer
        than ``ECHO_S`` is a link slower than the screen (its backlog grows): frames ``BACK_OFF`` times
        further apart, at most once a second (the answers lag the frames by the backlog), up to
        ``SLOWEST_S``; under half of it, ``BACK_OFF`` times closer again, as often, down to the asked-for
        ``frame_s`` (and the punctual ticks, ``_adapt``)."""
        now = self.clock()
        if now < self._echo_hold:
            return
        if round_trip_s > self.ECHO_S:
            self._echo_hold = now + 1.0
            self._punctual = 0
            slower = min(self.SLOWEST_S, self.frame_s * self.BACK_OFF)
            if slower > self.frame_s:
                self.frame_s = slower
                self.backed_off += 1
        elif round_trip_s < self.ECHO_S / 2 and self.frame_s > self.asked_s:
            self._echo_hold = now + 1.0
            self.frame_s = max(self.asked_s, self.frame_s / self.BACK_OFF)

    @property
    def stretch(self) -> float:
        """How many times further apart the frames are than asked (1: as asked)."""
        return self.frame_s / self.asked_s


class FrameSampler:
    """Samples a :class:`RobotSession` and the pollers' answers into one :class:`Frame`.

    ``clock`` is injected (monotonic seconds) so tests step time by hand. Not thread-safe: the shell
    calls it on its own thread; the sources it reads have their own locks."""

    def __init__(
        self,
        session: RobotSession,
        settings: Settings,
        clock: Callable[[], float] = time.monotonic,
        tracker: TrackerClient | None = None,
        sweep_pause: SweepPause | None = None,
    ):
        self.session = session
        self.settings = settings
        self.clock = clock
        # client-side simulation: no backend, so no topics answer will ever come (the screen says why)
        self.frame = Frame(topics=TopicsState(unavailable=NO_BACKEND)) if settings.mode == SIM else Frame()
        self.tracker = tracker  # the tracker the pollers ask (None: none yet)
        self.start_error: str | None = None
        self._slow_at = {ANALYTICS: float("-inf"), LATENCY: float("-inf"), TOPICS: float("-inf")}
        self.slow_stretch = 1.0  # the slow parts' period stretched with the frames' (FrameClock.stretch)
        self._count_at = float("-inf")
        self._topics: TopicsState | None = None  # the last topics answer, for the next slow frame
        self.robot_side: RobotSideView | None = None  # observe mode: the robot-side controller's last answer
        self.recording: AnalyticsView | None = None  # a file shown instead of the live analytics
        self._tracker_answer = TrackerAnswer()  # the tracker's last answer, as its poller handed it on
        self._sweep_version = -1  # the store version the measured p95 is from
        self._sweep_failed_at = float("-inf")  # when the last sweep failed (tried again SWEEP_RETRY_S on)
        # holds the sweep's child while the robot drives, where the console has no core to spare
        self.sweep_pause = sweep_pause if sweep_pause is not None else SweepPause(cores_available)

    # -- what the pollers and workers bring -----------------------------------------------------------
    def topics_polled(self, state: TopicsState) -> None:
        """A topics answer: shown with the next frame that takes the slow parts."""
        self._topics = state

    def recording_opened(self, view: AnalyticsView | None) -> None:
        """A recording to show instead of the live session's analytics (None: the live session again);
        shown with the next frame that takes the analytics part (the shell forces one)."""
        self.recording = view

    def robot_side_polled(self, view: RobotSideView) -> None:
        """The robot-side controller's answer (observe mode): shown with the next frame."""
        self.robot_side = view

    def observed(self) -> Observed | None:
        """Observe mode: what the panel and the map show of the observed controller."""
        st, observer = self.settings, self.session.observer
        if not st.observe or observer is None:
            return None
        goal = observer.current_goal
        return Observed(
            label=st.observe_label,
            goal=None if goal is None else (round(goal[0], 2), round(goal[1], 2)),
            run=observer.current_run,
            robot_side=self.robot_side,
        )

    def sweep_changed(self, view: LinkSweepView) -> None:
        """The sweep started, ended or failed (only a running sweep is ever paused)."""
        if view.state == FAILED:
            self._sweep_failed_at = self.clock()
        self.frame = replace(
            self.frame, link_sweep=replace(view, paused=view.paused and view.state == RUNNING)
        )

    def sweep_wanted(self) -> str | None:
        """The mission whose error-vs-latency sweep the analytics screen needs and has not (live only):
        another mission's, or this one's again ``SWEEP_RETRY_S`` after it failed; marks it running."""
        view = self.frame.link_sweep
        mission = self.session.loop.mission_name
        if not self.settings.live or view.state == RUNNING:
            return None
        retry = view.state == FAILED and self.clock() - self._sweep_failed_at >= SWEEP_RETRY_S
        if view.mission == mission and not retry:
            return None
        self.sweep_changed(replace(view, state=RUNNING, mission=mission, curve=None, error=""))
        return mission

    # -- one frame -----------------------------------------------------------------------------------------
    def sample(self, shown: Shown, force: bool = False, echo: bool = False) -> Frame:
        """The next frame: what ``shown`` shows, sampled now; ``force`` (a user action, a screen shown)
        takes every part at once; ``echo`` (a key that changed a command or a limit) the robot panel
        alone, and the status line where more than its count changed: the key's echo is a frame of what
        the key changed, the size of the panel, not of everything that changed since the last frame (on
        a slow link a frame's bytes are its time on the wire: docs/benchmarks/screen-bytes.md). The
        map and the rest follow with the next frame.

        Fast parts (the robot panel, the map) change at every frame; each slow part (analytics, latency,
        topics; the status line's sample count with any of them) at most ``analytics_rate`` times a
        second, one slow part a frame, the one waiting longest. On the dashboard a frame with a slow part
        leaves the fast ones as they were. Textual repaints every widget inside the box around all that
        changed in a frame: parts far apart that change in one frame cost a whole-screen repaint, which
        at 200x60 under a Pi-class quota took longer than a control period (bench/pi.py); one region a
        frame costs that region."""
        s = self.session
        now = self.clock()
        f = self.frame
        if echo and not force:
            return self._echo(shown, now)
        period = self.slow_stretch / self.settings.analytics_rate
        due = [part for part, at in self._slow_at.items() if shown.shows(part) and now - at >= period]
        slow = set(self._slow_at) if force else set(due and [min(due, key=self._slow_at.__getitem__)])
        for part in slow:
            self._slow_at[part] = now
        # the sample count follows in a frame that takes a slow part; where no slow part is shown (the
        # control screen below the dashboard's size), in any frame, at most every COUNT_PERIOD_S
        counts = bool(slow) or not any(shown.shows(part) for part in self._slow_at)
        status = self._status(f.status, now, counts, force)
        robot, trail, analytics, latency, sweep = f.robot, f.map, f.analytics, f.latency, f.link_sweep
        if shown.screen == CONTROL and (force or not (slow and shown.dashboard)):
            observed = self.observed()
            robot = _kept(f.robot, robot_view(s.link, s.loop, s.too_small, observed=observed))
            trail = _kept(f.map, map_view(s.link, s.loop, f.map, observed=observed))
        if ANALYTICS in slow and shown.shows(ANALYTICS):
            if self.recording is not None:  # a file instead of the live session: as it was read
                analytics = _kept(f.analytics, self.recording)
            else:  # (after a file, from scratch: nothing of the file's view is the live one's)
                analytics = analytics_view(s.store, None if f.analytics.source else f.analytics, s.loop)
            sweep = self._measured_p95(sweep)
            if sweep.paused != (self.sweep_pause.paused and sweep.state == RUNNING):
                sweep = replace(sweep, paused=not sweep.paused)
        if LATENCY in slow and shown.shows(LATENCY):
            # not at the UI rate: the console's own figures change with every round trip, and a line
            # repainted at the UI rate made every frame span the screen below it (bench/pi.py)
            latency = _kept(f.latency, self.latency())
        topics = f.topics
        if TOPICS in slow:
            answer = self._topics if self._topics is not None else topics
            self._topics = None
            if answer is not topics or topics.echo != s.echo.current:
                topics = replace(answer, echo=s.echo.current)
        parts = (_kept(f.status, status), robot, trail, analytics, latency, topics, sweep)
        if any(new is not old for new, old in zip(parts, astuple_shallow(f), strict=True)):
            self.frame = Frame(*parts)
        return self.frame  # nothing changed: the same frame, which the shell then does not hand on

    def _echo(self, shown: Shown, now: float) -> Frame:
        f = self.frame
        status = _kept(f.status, self._status(f.status, now, False, False))
        robot = f.robot
        if shown.screen == CONTROL:
            robot = _kept(f.robot, robot_view(self.session.link, self.session.loop, self.session.too_small,
                                              observed=self.observed()))  # fmt: skip
        if status is not f.status or robot is not f.robot:
            self.frame = replace(f, status=status, robot=robot)
        return self.frame

    def latency_polled(self, answer: TrackerAnswer) -> None:
        """The tracker's poller brought an answer: shown with the next frame that takes it."""
        self._tracker_answer = answer

    def tracker_view(self) -> TrackerAnswer | None:
        """What the tracker's poller last brought (None: simulated, or no tracker)."""
        if self.settings.mode == SIM or self.tracker is None:
            return None
        return self._tracker_answer

    def latency(self) -> LatencySnapshot:
        st = self.settings
        return latency_snapshot(
            self.tracker_view(), self.session.link, st.offset_warn_ms, st.mode == SIM, st.tracker_url or ""
        )

    def status(self) -> StatusView:
        s = self.session
        simulated = self.settings.mode == SIM
        observing = self.settings.observe_label if self.settings.observe else None
        shown_file = None if self.recording is None else self.recording.source
        side = self.robot_side  # observe mode: the robot-side controller, while it drives, not "manual"
        return status_view(
            s.link, self.target(), s.loop, s.store, self.tracker_view(), simulated, self.start_error,
            observing=observing, recording=shown_file, driving=None if side is None else side.driving,
            robot=self.settings.robot_name,
        )  # fmt: skip

    def _status(self, shown: StatusView, now: float, slow: bool, force: bool) -> StatusView:
        """The status line; a change of the sample count alone shows in a slow frame, at most every
        ``COUNT_PERIOD_S`` (``force``: at once).

        While recording, the count changes with every sample (10 a second), and a status line repainted
        that often made every repaint span the whole screen: Textual renders every widget inside the box
        around all dirty regions, and the status line is the top row (py-spy and render counts at
        200x60, bench/pi.py)."""
        status = self.status()
        if (
            status != shown
            and replace(status, points=shown.points) == shown
            and not force
            and (not slow or now - self._count_at < COUNT_PERIOD_S)
        ):
            return shown
        if status.points != shown.points:
            self._count_at = now
        return status

    def _measured_p95(self, view: LinkSweepView) -> LinkSweepView:
        """The p95 of the latencies recorded, on the error-vs-latency plot (when the store changed)."""
        store = self.session.store
        if self._sweep_version == store.version:
            return view
        self._sweep_version = store.version
        p95 = measured_p95(store.column("latencyMs"))
        return view if p95 == view.p95_ms else replace(view, p95_ms=p95)

    def target(self) -> str:
        """What the console talks to, for the status line."""
        st = self.settings
        if st.mode == SIM:
            return ""  # the link state already says SIMULATED
        if st.mode == "embedded":
            transport = " ros" if st.transport == "ros" else ""
            if self.session.link.state == STARTING:
                return f"embedded{transport}"
            bridge = st.rosbridge_url.rsplit(":", 1)[-1]
            api = (st.tracker_url or "").rsplit(":", 1)[-1]
            return f"embedded{transport} {bridge}/{api}"
        return f"connect {st.rosbridge_url}"

    def user_state(self) -> tuple[object, ...]:
        """What a key press may change that the user waits to see (a held key's repeats that change
        none of it wait for the next UI tick)."""
        s = self.session
        return (s.loop.command, s.teleop.speed, s.teleop.turn, s.too_small, s.loop.mission_name)
