"""An rclpy executor spun in a thread of its own, under the backend's supervisor: the relay's nodes
(``backend.py``) and the provided servers (``interfaces.py``) each have one. A callback that raises
ends ``spin``: the supervisor logs it once and spins again (``supervise.py``), where it stopped for
good, and with it the tracker's watchdog; so the executor that spins the tracker never gives up
(``give_up=False``: it is the robot's stop) and, while it is down, the tracker holds commands
(``nodes.TrackerNode.executor_changed``). The worker's beat is a timer of its own on one of the
executor's nodes: a callback like the others (an injected failure is raised from it), which an
executor that stopped spinning no longer calls."""

from __future__ import annotations

import contextlib
import threading

from rclpy.executors import Executor, ExternalShutdownException
from rclpy.node import Node

from ..supervise import Supervisor

BEAT_S = 0.5  # the executor's beat: it is ``running`` from its first (``supervise.Supervisor.beat``)


def spin_in_thread(
    executor: Executor,
    node: Node,
    name: str,
    supervisor: Supervisor,
    stop: threading.Event,
    give_up: bool = True,
) -> threading.Thread:
    """Spin ``executor`` in a supervised daemon thread called ``name`` until it shuts down (set ``stop``
    first: a failure then is not followed by a restart); its beat is a timer on ``node``, one of its
    nodes."""
    node.create_timer(BEAT_S, lambda: supervisor.beat(name))

    raised: list[BaseException] = []  # the last error that ended a spin

    def spin() -> None:
        with contextlib.suppress(ExternalShutdownException):  # the context went first
            while True:
                try:
                    executor.spin()
                    return
                except Exception as exc:
                    # a MultiThreadedExecutor may hand one callback's error out twice (it yields a task
                    # again while its pool runs it): one failure, counted once
                    if raised and exc is raised[0]:
                        continue
                    raised[:] = [exc]
                    raise

    return supervisor.thread(name, spin, stop, give_up=give_up)
