"""The part of a stop that reaches beyond the console's own commands (``control/stop.py`` says what, by
mode), done on a thread of its own so that no key, paint or slow server waits for it.

A stop asked for while another is being done is done again once that one ends (a second press is
never lost, and never runs twice at once). For each stop, at once and together: the robot-side
controller is asked to stop (``DELETE /api/autonomy``), every goal of each configured action server is
cancelled, and zero velocity goes on the observed command topic at ``ZERO_HZ`` until ``ZERO_FOR_S``
after the last answer (or ``CANCEL_TIMEOUT_S``). Then one :class:`~..control.stop.StopReport` goes to
``on_report``.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ..control.stop import (
    CANCEL_ALL,
    CANCEL_SUFFIX,
    CANCEL_TIMEOUT_S,
    ZERO_FOR_S,
    ZERO_HZ,
    ActionCancel,
    Cancel,
    RobotSideStop,
    StopReport,
    StopScope,
    cancel_failure,
    cancel_outcome,
)
from ..latency.autonomy import AutonomyUnavailable
from ..link.base import CONNECTED, Link, ReachesOthers

if TYPE_CHECKING:  # the client imports httpx: the session side (and compare) load it only when asked
    from ..latency.autonomy_client import AutonomyClient

log = logging.getLogger(__name__)
SAME_PRESS_S = 0.3


class RemoteStop:
    def __init__(
        self,
        scope: StopScope,
        link: Callable[[], Link],
        autonomy: Callable[[], AutonomyClient | None],
        on_report: Callable[[StopReport], None] = lambda report: None,
    ) -> None:
        self.scope = scope
        self._link = link
        self._autonomy = autonomy
        self.on_report = on_report
        self._wake = threading.Condition()
        self._asked = 0  # stops asked for
        self._done = 0  # stops done (the last one asked, when both are equal)
        self._thread: threading.Thread | None = None
        self._closed = False
        self._requested_at = float("-inf")
        self.reports: list[StopReport] = []  # the last few (tests and the bench read them)

    def request(self) -> None:
        """Ask for a stop (any thread; returns at once). A second request within ``SAME_PRESS_S`` is the
        same press answered twice (ctrl+k: on the input thread, then by the UI in its place): one stop."""
        if not self.scope.remote:
            return
        now = time.monotonic()
        with self._wake:
            if self._closed or now - self._requested_at < SAME_PRESS_S:
                return
            self._requested_at = now
            self._asked += 1
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="remote-stop", daemon=True)
                self._thread.start()
            self._wake.notify_all()

    def wait_idle(self, timeout: float) -> bool:
        """Until every stop asked for is done (tests)."""
        with self._wake:
            return self._wake.wait_for(lambda: self._done >= self._asked, timeout)

    def close(self) -> None:
        with self._wake:
            self._closed = True
            self._wake.notify_all()

    def _run(self) -> None:
        while True:
            with self._wake:
                self._wake.wait_for(lambda: self._asked > self._done or self._closed)
                if self._closed:
                    return
                asked = self._asked
            try:
                report = self.stop_once()
            except Exception:  # the stop thread never dies: the next press must work
                log.exception("a remote stop failed")
                report = StopReport(link_down=True)
            self.reports = [*self.reports[-9:], report]
            with self._wake:
                self._done = asked
                self._wake.notify_all()
            self.on_report(report)

    def stop_once(self) -> StopReport:
        """One stop: the asks, the zeros, the report (on the calling thread; blocks about a second in
        observe mode)."""
        scope, link = self.scope, self._link()
        reaches = isinstance(link, ReachesOthers) and link.state == CONNECTED
        answers: dict[str, ActionCancel] = {}
        lock = threading.Lock()
        arrived = threading.Event()

        def answered(action: str, outcome: ActionCancel) -> None:
            with lock:
                answers.setdefault(action, outcome)
                if len(answers) == len(scope.actions):
                    arrived.set()

        if not scope.actions or not reaches:
            arrived.set()
        elif isinstance(link, ReachesOthers):
            for action in scope.actions:

                def done(ok: bool, values: Any, a: str = action) -> None:
                    answered(a, cancel_outcome(a, values) if ok else cancel_failure(a, values))

                sent = link.call_service(action + CANCEL_SUFFIX, CANCEL_ALL, CANCEL_TIMEOUT_S, done)
                if not sent:
                    answered(action, ActionCancel(action, Cancel.FAILED, detail="the link is down"))
        robot_side = self._ask_robot_side() if scope.robot_side else None  # meanwhile the cancels travel
        zeroed = False
        if scope.zero_topic is not None and reaches and isinstance(link, ReachesOthers):
            self._zeros(link, scope.zero_topic, arrived)
            zeroed = True
        arrived.wait(CANCEL_TIMEOUT_S)
        with lock:
            cancels = tuple(
                answers.get(a, ActionCancel(a, Cancel.FAILED, detail=f"no answer in {CANCEL_TIMEOUT_S:g} s"))
                for a in scope.actions
            )
        return StopReport(
            robot_side=robot_side,
            cancels=cancels if reaches else (),
            zero_topic=scope.zero_topic if zeroed else None,
            zero_for_s=ZERO_FOR_S if zeroed else 0.0,
            link_down=not reaches and bool(scope.actions or scope.zero_topic),
        )

    def _ask_robot_side(self) -> RobotSideStop:
        client = self._autonomy()
        if client is None:
            return RobotSideStop(error="no tracker to ask", enabled=False)
        try:
            status = client.stop()
        except AutonomyUnavailable as exc:
            return RobotSideStop(error=str(exc), enabled=not exc.disabled)
        return RobotSideStop(stopped=status.stopped, run=status.run())

    def _zeros(self, link: ReachesOthers, topic: str, arrived: threading.Event) -> None:
        """Zero velocity on ``topic`` at ``ZERO_HZ`` from now until ``ZERO_FOR_S`` after the cancels'
        answers came (or ``CANCEL_TIMEOUT_S`` passed): paced on the clock, so the robot's driver sees a
        steady rate of zeros."""
        period = 1.0 / ZERO_HZ
        start = nxt = time.monotonic()
        end: float | None = None
        while True:
            now = time.monotonic()
            if end is None and (arrived.is_set() or now - start >= CANCEL_TIMEOUT_S):
                end = now + ZERO_FOR_S
            if end is not None and now >= end:
                return
            link.publish_zero(topic, self.scope.zero_stamped)
            nxt += period
            pause = max(0.0, nxt - time.monotonic())
            if end is None:
                arrived.wait(pause)  # an answer ends the wait early: the end is set at once
                if arrived.is_set() and time.monotonic() < nxt:
                    continue
            else:
                time.sleep(pause)


__all__ = ["RemoteStop"]
