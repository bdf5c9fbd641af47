"""The robot session's clock: its clocked work on a thread of its own, on a monotonic schedule, so a
slow paint never delays a command (the robot's clock is not the UI's clock).

Three jobs, each at its own period: the control tick (``--repeat-rate``), sampling
(``--collection-rate``) and stepping the client-side simulator (50 Hz; a link with nothing to step is
asked four times a second). After a control tick that published, the command is on the socket before
anything else of this thread takes the GIL (``_written``); then the paint that gave way goes on
(``give_way``), the tick's lateness is measured, the collector may run, and the frame hook is called.
The session (``robot.py``) takes commands and owns the link; this module owns the thread, the due
times and their counters. No Textual.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from ..latency.clocksync import LatencyMeter
from .collector import TickCollector

SWITCH_INTERVAL_S = 0.001
NO_STEP_RECHECK_S = 0.25  # how often a link with nothing to step is asked again
WRITE_WAIT_S = 0.02  # a tick waits at most this long for its command to be written (_written)


def next_due(due: float, started: float, period: float) -> float:
    """When a clocked job that was due at ``due`` and started at ``started`` runs next (monotonic s).

    One period after ``due`` (its grid) when it started less than half a period late, so wake-up delays
    never slow the rate. One period after it *started* when it started later than that: after a stall
    (the process stopped, the CPU quota spent, the garbage collection after the last control tick ran
    past this one's time) the next command leaves a period after the late one, never in a burst behind
    it -- and never a whole extra period later, as when the grid restarted from the end of the job."""
    on_grid = due + period
    return on_grid if started - due <= period / 2 else started + period


@dataclass(frozen=True)
class Jobs:
    """What the clock runs and reads, given by the session."""

    tick: Callable[[], bool]  # the control tick: True when it handed the link a command it took
    sample: Callable[[], object]
    step: Callable[[], bool]  # one step of an in-process link; False: the link has none (asked again later)
    meter: Callable[[], LatencyMeter]  # the link's meter (the link may be replaced while running)
    driving: Callable[[], bool]  # a mission runs or a key drives
    control_s: float
    sample_s: float
    step_s: float


class Schedule:
    def __init__(self, jobs: Jobs) -> None:
        self.jobs = jobs
        self.on_tick: Callable[[], None] = lambda: None  # after each control tick, on this thread
        self.late_ticks = 0  # ticks that ran more than one period late
        self.driving = False  # a mission runs or a key drives, as of the last control tick
        self.tick_late_s = 0.0  # how late the newest command left, after its tick's due time
        self.collector = TickCollector()  # full garbage collections just after a tick (the thread's own)
        self.tick_due_s = float("inf")  # when the next control tick is due (monotonic)
        self.ticks_written = 0  # control ticks done with their command (written, none, or waited 20 ms for)
        self.gave_way = 0  # times the UI waited for a tick (give_way: tests and the bench read it)
        self._tick_written = threading.Condition(threading.Lock())
        self._thread: threading.Thread | None = None
        self._stopping = threading.Event()

    def start(self) -> None:
        """Run the clocked work on a thread of its own until :meth:`stop`."""
        if self._thread is None:
            # A thread that wants the GIL asks the holder to let go after the switch interval; 5 ms by
            # default is 20 ms of wall time at a Pi-class CPU quota, per hand-off (session, then Twisted's
            # reactor). 1 ms keeps a command's way through both threads short while the UI paints.
            sys.setswitchinterval(SWITCH_INTERVAL_S)
            self._thread = threading.Thread(target=self._run, name="robot-session", daemon=True)
            self._thread.start()

    def stop(self, timeout: float = 2.0) -> None:
        self._stopping.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=timeout)

    def _run(self) -> None:
        self.collector.begin()
        try:
            self._run_clocked()
        finally:
            self.collector.end()

    def _run_clocked(self) -> None:
        j = self.jobs
        periods: dict[Callable[[], object], float] = {
            j.tick: j.control_s, j.sample: j.sample_s, j.step: j.step_s
        }  # fmt: skip
        now = time.monotonic()
        due = {job: now + period for job, period in periods.items()}
        self.tick_due_s = due[j.tick]
        last_due: float | None = None
        while not self._stopping.is_set():
            job = min(due, key=due.__getitem__)
            wait = due[job] - time.monotonic()
            if wait > 0 and self._stopping.wait(wait):
                break
            started = time.monotonic()
            written = j.meter().sent
            published = job()
            upcoming = next_due(due[job], started, periods[job])
            if job == j.step and not published:  # nothing to step (a rosbridge link): 4 wake-ups a second
                upcoming = started + NO_STEP_RECHECK_S  # instead of 50 (the link may still be replaced)
            if job == j.tick:
                self._written(written, bool(published))  # before the frame and a collection take the GIL
                with self._tick_written:  # a paint that gave way goes on (give_way)
                    self.tick_due_s = upcoming
                    self.ticks_written += 1
                    self._tick_written.notify_all()
                self.tick_late_s = self._lateness(due[job], last_due)
                last_due = due[job]
                self.driving = j.driving()
                self.collector.after_tick(driving=self.driving)
                self.on_tick()
                if started - due[job] > periods[job]:
                    self.late_ticks += 1
            due[job] = upcoming

    def _written(self, written: int, published: bool) -> None:
        """The command this tick published is on the socket before anything else of this thread's
        tick takes the GIL: the frame it asks for (``on_tick``) and a garbage collection.

        ``RosLink`` stamps and writes each command on its reactor's thread. A collection that started
        first held that thread between the stamp and the write (measured: one-way latency up to 19 ms
        instead of under 2 ms at a Pi-class quota, collections every 0.2 s); a frame asked for first
        woke the UI thread, which then took the GIL before the reactor's thread (and, under a quota,
        the rest of the scheduling period): the command left late, or stalled between its stamp and
        the socket (bench/pi.py, a packet capture on the loopback: 9-19 ms). A link that writes in
        the call (the simulator) or meters nothing has ``sent`` 0 and is not waited for."""
        meter = self.jobs.meter()
        if published and meter.sent > 0:
            meter.wait_sent(written, WRITE_WAIT_S)

    def _lateness(self, due_s: float, last_due_s: float | None) -> float:
        """How late the commands left: this tick's own end, or the newest command's write to the
        socket (on the link's thread, so usually the previous tick's) after its tick's due time."""
        late = time.monotonic() - due_s
        sent = self.jobs.meter().last_send_mono
        if sent is not None and sent >= due_s:  # this tick's command is written already
            late = max(late, sent - due_s)
        elif sent is not None and last_due_s is not None and sent >= last_due_s:
            late = max(late, sent - last_due_s)
        return max(0.0, late)

    def give_way(self, guard_s: float) -> bool:
        """On the UI's thread, between the widgets of a paint: when the next control tick is due within
        ``guard_s``, wait until it has run and its command is written (at most ``guard_s`` more than
        its due time). True when it saw the tick run; False when it did not wait, or gave up.

        A paint at 200x60 on a Pi-class quota takes 60-100 ms of wall time, most of a control period,
        and one that was still running at a tick's time spent the quota of that scheduling period: the
        tick waited for the next one, then for the GIL, 10-40 ms in all (bench/render_overlap.py). A
        paint that stops short of the tick instead leaves the quota and the GIL to the session's and
        the link's threads. The shell asks only where the console has no core to spare."""
        with self._tick_written:  # the due time and the count read together: no wake-up is missed
            now = time.monotonic()
            due, seen = self.tick_due_s, self.ticks_written
            if not 0.0 < due - now <= guard_s or self._stopping.is_set():
                return False
            ran = self._tick_written.wait_for(lambda: self.ticks_written != seen, due - now + guard_s)
        self.gave_way += 1
        return ran
