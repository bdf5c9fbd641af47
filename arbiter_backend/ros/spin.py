"""An rclpy executor spun in a thread of its own: the relay's nodes (``backend.py``) and the provided
servers (``interfaces.py``) each have one."""

from __future__ import annotations

import logging
import threading

from rclpy.executors import Executor, ExternalShutdownException

log = logging.getLogger(__name__)


def spin_in_thread(executor: Executor, name: str, what: str) -> threading.Thread:
    """Spin ``executor`` in a daemon thread called ``name`` until it shuts down; an error that stops it
    is logged as ``what`` stopping."""

    def spin() -> None:
        try:
            executor.spin()
        except ExternalShutdownException:
            pass
        except Exception:
            log.exception("%s stopped", what)

    thread = threading.Thread(target=spin, name=name, daemon=True)
    thread.start()
    return thread
