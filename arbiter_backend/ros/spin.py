"""An rclpy executor spun in a thread of its own, under the backend's supervisor: the relay's nodes
(``backend.py``) and the provided servers (``interfaces.py``) each have one. A callback that raises
ends ``spin_once``: the supervisor logs it once and spins again (``supervise.py``), where a bare
``executor.spin()`` stopped for good, and with it the tracker's watchdog."""

from __future__ import annotations

import threading

from rclpy.executors import Executor, ExternalShutdownException

from ..supervise import Supervisor

SPIN_S = 0.5  # the longest spin_once waits: a stop (or a beat) is seen within it


def spin_in_thread(
    executor: Executor, name: str, supervisor: Supervisor, stop: threading.Event
) -> threading.Thread:
    """Spin ``executor`` in a supervised daemon thread called ``name`` until ``stop`` is set (set it
    before ``executor.shutdown``) or its context shuts down."""

    def spin() -> None:
        while not stop.is_set():
            try:
                executor.spin_once(timeout_sec=SPIN_S)
            except ExternalShutdownException:
                return
            supervisor.beat(name)

    return supervisor.thread(name, spin, stop)
