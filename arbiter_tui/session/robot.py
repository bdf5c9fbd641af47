"""The robot session: one object that drives the robot and records what it did, with no Textual.

It owns the link, teleop, the control loop, the analytics store (the seed's ``useAnalyticsEngine``: one
per robot session, outliving screen switches), the stop and the exports, and takes the commands. Its
clocked work -- the control tick at ``--repeat-rate``, sampling at ``--collection-rate``, stepping the
client-side simulator at 50 Hz and expiring unanswered commands -- is run by ``schedule.py`` on a thread
of its own, so a slow paint never delays a command (the robot's clock is not the UI's clock). The
Textual shell turns keys into
the commands below and samples the session into frozen snapshots at its own pace; ``arbiter-tui
compare`` and tests drive the same session without Textual (``live=False``: the caller ticks it).

Thread safety: every command and every tick takes ``lock`` (an RLock held for microseconds); the store
and the link's telemetry have locks of their own. Events (a mission finished) go to ``on_event``, which
the shell points at its thread-safe ``post_message``.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from arbiter_core.controllers import MANUAL, choose_controller_hint, goal_driver
from arbiter_core.simulator import RATE_HZ as SIM_HZ
from arbiter_core.topicstats import TopicFigures

from ..analytics.files import (
    FORMATS,
    Collected,
    ExportError,
    NothingToExport,
    collected,
    export_stem,
    export_store,
)
from ..analytics.observe import ObserveConfig, Observer
from ..analytics.store import AnalyticsStore, DataPoint
from ..control.loop import ControlLoop
from ..control.stop import StopReport, StopScope, stop_scope
from ..control.teleop import MOVE_KEYS, SCALE_KEYS, STOP_KEYS, Teleop
from ..latency.autonomy import AutonomyUnavailable, RobotSideView
from ..link.base import DISCONNECTED, RECONNECTING, STARTING, Link, Observes, Stepped
from .echo import TopicEcho
from .heartbeat import OperatorWatch
from .journal import Journal, Sources
from .remote_stop import RemoteStop
from .schedule import Jobs, Schedule
from .settings import SIM, Settings

if TYPE_CHECKING:  # the client imports httpx: the session side (and compare) load it only when asked
    from ..latency.autonomy_client import AutonomyClient

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ExportResult:
    fmt: str
    path: Path | None
    points: int
    error: str | None = None
    nothing: bool = False  # refused: no samples to export (not a failure)


@dataclass(frozen=True)
class StopDone:
    """A stop's remote part ended (``remote_stop.py``): what it did, in words."""

    report: StopReport


@dataclass(frozen=True)
class JournalSaid:
    """The journal could not go on (a full disk, an unwritable directory): one line."""

    text: str


@dataclass(frozen=True)
class MissionFinished:
    """A mission (or a goal) was completed."""

    algorithm: str
    mission: str


DEFAULT_CONTROL_HZ = 10.0  # the control tick when no --repeat-rate ceiling is set
NO_LINK_WORDS = "The link to the robot is down: nothing can be sent. Press g once it is back."


class RobotSession:
    def __init__(
        self,
        config: Settings,
        link: Link,
        store: AnalyticsStore | None = None,
        clock: Callable[[], float] = time.monotonic,
        wall_ms: Callable[[], float] = lambda: time.time_ns() / 1e6,
    ) -> None:
        self.config = config
        self.lock = threading.RLock()
        self.link = link
        self.clock = clock
        self.store = store if store is not None else AnalyticsStore(config.max_points, config.collection_rate)
        # the settings are read here once: their defaults live in one place (settings.Settings)
        self.store.collection_rate = config.collection_rate
        if self.store.max_data_points != config.max_points:
            self.store.max_data_points = config.max_points
        if not config.start_paused and not self.store.is_collecting and len(self.store) == 0:
            self.store.start_collection()  # recording is on unless asked otherwise (r pauses it)
        self.teleop = Teleop(speed=config.speed, turn=config.turn, key_timeout=config.key_timeout)
        self.loop = ControlLoop(link, self.store, self.teleop, wall_ms, max_rate=config.repeat_rate)
        # observe mode: the robot's own topics make the samples and runs (analytics/observe.py)
        self.observer = (
            Observer(self.store, ObserveConfig(label=config.observe_label, rate_hz=config.collection_rate))
            if config.observe
            else None
        )
        self._unobserve: Callable[[], None] | None = None
        self._observed_life: int | None = None
        self._observed_telemetry: object = None
        self._observe(link)
        self.echo = TopicEcho()  # the topics screen's echo of one topic
        # what a stop reaches beyond the console's own commands (control/stop.py), done on its own thread
        self.autonomy: AutonomyClient | None = None  # the backend's robot-side controller API, once known
        self.stop_scope = stop_scope(
            config.mode == SIM, config.observe, config.namespace, config.cmd_topic, config.cmd_stamped,
            config.stop_actions,
        )  # fmt: skip
        # a session that is not live (a still for tests, `compare`'s engine) asks nothing of anyone
        self.remote_stop = RemoteStop(
            self.stop_scope if config.live else StopScope(), lambda: self.link, lambda: self.autonomy,
            lambda r: self.on_event(StopDone(r)),
        )  # fmt: skip
        self.last_export: ExportResult | None = None
        # what it records, on disk as it goes (session/journal.py), where the command line asks
        self.journal = _journal_of(self) if config.journal_dir is not None and config.live else None
        self.too_small = False
        self.stop_reason: str | None = None
        self.on_event: Callable[[object], None] = lambda event: None
        # does the person's terminal still hear the console? (heartbeat.py; the shell arms it)
        self.operator = OperatorWatch(config.operator_timeout, lambda e: self.on_event(e))
        self._robot_side_started = False  # observe mode: g started the robot-side controller
        self.ticks = 0  # control ticks run (tests and the bench read it)
        self.published = False  # the last control tick handed the link a command
        self._was_running = False
        # the clocked work (control, sampling, the simulator) on a thread of its own (schedule.py)
        self.schedule = Schedule(
            Jobs(
                tick=self.tick_control, sample=self.sample, step=self.step_link,
                meter=lambda: self.link.telemetry.meter,
                driving=lambda: self.loop.running or self.teleop.moving,
                control_s=1.0 / (config.repeat_rate or DEFAULT_CONTROL_HZ),
                sample_s=1.0 / config.collection_rate, step_s=1.0 / SIM_HZ,
            )
        )  # fmt: skip

    # -- the link ---------------------------------------------------------------------------------
    def attach(self, link: Link) -> None:
        """The real link replaces the pending one (the embedded backend started in a worker)."""
        with self.lock:
            self.link = link
            self.loop.link = link
        self._observe(link)

    def _follow_observed_life(self) -> None:
        """Observe mode: a new odometry life (the link lost, the pose jumped) ends the observed run and
        leaves a gap in the record (the session's thread, before each control tick)."""
        life = self.link.telemetry.life
        if self.observer is not None and life != self._observed_life:
            if self._observed_life is not None and self._observed_telemetry is self.link.telemetry:
                self.observer.lost()
            self._observed_life, self._observed_telemetry = life, self.link.telemetry

    def _observe(self, link: Link) -> None:
        if self.observer is None or not isinstance(link, Observes):
            return
        if self._unobserve is not None:
            self._unobserve()
        c = self.config
        self._unobserve = link.observe(
            self.observer, c.cmd_topic, c.cmd_stamped, c.plan_topic, c.goal_topic, c.status_topic
        )

    def echo_topic(self, figures: TopicFigures | None) -> None:
        """Echo the topic ``figures`` describes on the topics screen (None: stop), through the link."""
        self.echo.show(self.link, figures)

    def link_down(self) -> bool:
        """The rosbridge link was lost (or never came up): nothing the console sends goes out."""
        return self.link.state in (DISCONNECTED, RECONNECTING)

    # -- the clocked work ---------------------------------------------------------------------------------
    def tick_control(self) -> bool:
        """One control tick: a held key's command or the controller's, and run bookkeeping. True when it
        handed the link a command the link took."""
        with self.lock:
            self.published = False
            self._follow_observed_life()
            self._hold_if_unheard()
            try:
                self.link.telemetry.meter.expire(time.monotonic())  # unreported commands become "lost"
                refused = self.loop.unsent
                # handed to the link, and taken (a link that is down refuses: nothing to wait for)
                self.published = (
                    self.loop.tick_control(self.clock()) is not None and self.loop.unsent == refused
                )
            except Exception:  # a failing link must not take the session (and its stop keys) down
                log.exception("control tick failed")
            self.ticks += 1
            running = self.loop.running
            finished = self._was_running and not running and self.loop.mission.done
            self._was_running = running
            event = MissionFinished(self.loop.algorithm, self.loop.mission_label) if finished else None
        if event is not None:
            self.on_event(event)
        return self.published

    def _hold_if_unheard(self) -> None:
        """The person's terminal has not answered for longer than the bound (``heartbeat.py``): nobody
        can see the robot, so what drives on its own holds: a mission stops where it is (one zero; g
        resumes it), and the robot-side controller the console started is asked to stop."""
        driving = None
        if self.loop.running:
            m = self.loop.mission
            driving = f"{m.label} ({self.loop.algorithm}, {m.reached}/{m.total} waypoints)"
        elif self._robot_side_started:
            driving = "the robot-side controller"
        if not self.operator.hold(time.monotonic(), driving):
            return
        self.stop("operator unheard")
        if self._robot_side_started:
            self._robot_side_started = False
            self.remote_stop.request()

    def sample(self) -> DataPoint | None:
        """One sample of the robot into the store (at the collection rate); the point recorded, if any."""
        if self.observer is not None:
            return None  # observing: the robot's odometry makes the samples, on the link's thread
        with self.lock:
            try:
                return self.loop.sample()
            except Exception:
                log.exception("sampling failed")
                return None

    def step_link(self) -> bool:
        """One step of a link that runs in-process (the simulator); False when the link has none."""
        link = self.link
        if isinstance(link, Stepped):
            with self.lock:
                link.step()
            return True
        return False

    def start(self) -> None:
        """Run the clocked work on the session's own thread until :meth:`close`, and the journal on its."""
        self.schedule.start()
        if self.journal is not None:
            self.journal.start()

    def close(self) -> None:
        """Stop the robot (one zero) and the clocked work; the journal is finished (a clean end)."""
        self.stop("quit")
        self.remote_stop.close()
        self.schedule.stop()
        if self.journal is not None:
            self.journal.close()

    def hang_up(self, reason: str) -> None:
        """The terminal went away (SIGHUP, SIGTERM): stop, and finish the journal now, saying so (the
        next start offers it: the person did not choose to end the session)."""
        self.stop(reason)
        if self.journal is not None:
            self.journal.close(reason)

    # -- commands (any thread) -------------------------------------------------------------------------
    def stop(self, reason: str) -> None:
        """Stop teleop and autonomy and send one zero now (best effort: never raises)."""
        with self.lock:
            self.stop_reason = reason
            self.loop.stop()
            with contextlib.suppress(Exception):
                self.loop.tick_control(self.clock())
            self._was_running = False

    def stop_all(self, reason: str) -> None:
        """The stop keys, from any screen, dialog or thread: the console's own driving stops now (one
        zero), and whatever else drives is asked to stop on the stop's own thread (``control/stop.py``
        says what that is in each mode; a ``StopDone`` event says what it did)."""
        with self.lock:
            self.stop(reason)
            self.loop.acknowledge()  # a stop is a key: the last run's "done" line goes
        self.remote_stop.request()

    def end_manual_hold(self, reason: str) -> None:
        """A held teleop key ends now (one zero); an autonomous run is left driving."""
        with self.lock:
            if self.teleop.moving:
                self.stop_reason = reason
                self.teleop.stop()
                with contextlib.suppress(Exception):
                    self.loop.tick_control(self.clock())

    def set_too_small(self, small: bool) -> None:
        """While the terminal is too small to show the console, the robot stands still."""
        with self.lock:
            if small and not self.too_small:
                self.stop("terminal too small")
            self.too_small = small

    def key(self, key: str, at: float | None = None) -> bool:
        """A key pressed on the control screen; True if teleop used it. ``at``: when it was read, on
        this session's clock (taken before this lock; now when not given)."""
        if at is None:
            at = self.clock()
        with self.lock:
            if key in STOP_KEYS:  # everywhere, whatever else holds: a stop
                self.stop_all("stop key")
                return True
            if self.too_small:
                return key in MOVE_KEYS or key in SCALE_KEYS  # swallowed: nothing moves unseen
            if key in MOVE_KEYS and self.loop.algorithm != MANUAL:
                # Manual keys take over from an autonomous controller (g resumes its mission): the run
                # ends as overridden before the key is pressed, once.
                self.loop.override()
            before = (self.teleop.moving, self.teleop.target)
            result = self.teleop.press(key, at)
            if result is None:
                return False
            self.loop.acknowledge()  # the last run's "done" stays until the next mission or key
            if result == "move" and (self.teleop.moving, self.teleop.target) != before:
                # a new key (or direction) is answered at once; a key's auto-repeats only keep it held,
                # and the control tick sends at --repeat-rate
                self.tick_control()
            return True

    def select_algorithm(self, name: str) -> None:
        with self.lock:
            self.loop.set_algorithm(name)

    def select_mission(self, name: str) -> None:
        with self.lock:
            self.loop.set_mission(name)

    def cycle_mission(self) -> None:
        with self.lock:
            self.loop.cycle_mission()

    def go(self, restart: bool = False) -> str | None:
        """``g``: resume an interrupted mission or start the selected one; ``restart``: from waypoint 1.
        Returns why nothing started (None when it did)."""
        with self.lock:
            if self.too_small:
                return "the terminal is too small"
            if self.link_down() or self.link.state == STARTING:
                return NO_LINK_WORDS  # a mission that cannot move says why, instead of "driving" at v 0
            started = self.loop.restart() if restart else self.loop.go()
            return None if started else choose_controller_hint()

    # -- the robot-side controller (observe mode: g starts it, the stop keys stop it) ------------------
    def robot_side(self) -> RobotSideView:
        """Ask the backend's robot-side controller how it is (blocking: a worker's thread)."""
        client = self.autonomy
        if client is None:
            return RobotSideView(known=True, text="no backend API to ask")
        try:
            status = client.status()
        except AutonomyUnavailable as exc:
            text = "off (the backend runs without --autonomy)" if exc.disabled else f"cannot ask: {exc}"
            return RobotSideView(known=True, enabled=False, text=text)
        run = "" if status.algorithm is None else status.run()
        return RobotSideView(
            known=True, enabled=True, running=status.running, text=status.state, run=run,
            algorithm=status.algorithm or "",
        )  # fmt: skip

    def start_robot_side(self) -> str:
        """``g`` in observe mode: the selected controller (go_to_goal when manual is selected) on the
        selected mission, started on the robot at the console's max speed and turn (blocking: a worker's
        thread). One line saying what happened; AutonomyUnavailable when the backend refused."""
        client = self.autonomy
        if client is None:
            raise AutonomyUnavailable("no backend API to ask")
        with self.lock:
            algorithm = goal_driver(self.loop.algorithm)
            mission, speed, turn = self.loop.mission_name, self.teleop.speed, self.teleop.turn
        status = client.start(algorithm, mission, speed, turn)
        self._robot_side_started = True
        return f"robot-side {status.run()}: started on the robot"

    def take_notice(self) -> str | None:
        """What the last ``g`` has to say beside starting (a mission forgotten since), once."""
        with self.lock:
            notice, self.loop.notice = self.loop.notice, None
            return notice

    def go_to(self, x: float, y: float) -> None:
        """Drive to (x, y) with go_to_goal (or the autonomous controller already selected)."""
        with self.lock:
            if not self.too_small:
                self.loop.go_to(x, y)

    def toggle_collection(self) -> None:
        if self.store.is_collecting:
            self.store.stop_collection()
        else:
            self.store.start_collection()

    def clear(self) -> int:
        n = len(self.store)
        self.store.clear()
        return n

    def collected(self) -> Collected:
        """The collected data now, as an export writes it: what the export chooser counts and writes.
        (The store's own lock, not the session's: a long copy never holds up a control tick or a stop.)"""
        return collected(self.store)

    def export(self, *formats: str, data: Collected | None = None) -> list[ExportResult]:
        """Write the collected data (``data``: as it was collected when asked, else now) in each format
        under one file stem, every format the same samples; nothing when there is none."""
        data = self.collected() if data is None else data
        n = len(data.points)
        stem = export_stem()
        results = []
        for fmt in formats:
            if fmt not in FORMATS:
                raise ValueError(f"unknown export format {fmt!r}")
            try:
                path = export_store(data, fmt, self.config.export_dir, stem=stem)
            except NothingToExport as exc:
                return [ExportResult(fmt, None, n, str(exc), nothing=True)]  # said once, whatever the formats
            except (ExportError, OSError, ValueError) as exc:
                results.append(ExportResult(fmt, None, n, str(exc)))
            else:
                results.append(ExportResult(fmt, path, n))
        if results:
            self.last_export = results[-1]
        return results


def _journal_of(session: RobotSession) -> Journal:
    """The session's journal (``journal.py``): its store and link figures, written under ``journal_dir``;
    what it says goes through the session's events (a function, not a method: RobotSession is at its
    bound of 30)."""
    c = session.config
    assert c.journal_dir is not None
    sources = Sources(session.store, lambda: session.link.telemetry.meter.samples())
    said = lambda text: session.on_event(JournalSaid(text))  # noqa: E731
    return Journal(sources, c.journal_dir, int(c.journal_max_mb * 1e6), said, lambda f: session.on_event(f))
