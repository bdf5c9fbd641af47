#!/usr/bin/env python
"""How fast the console's link notices a lost backend and comes back, over repeated trials.

Per trial, with the TUI's own ``RosLink`` against a backend subprocess:

* killed: SIGKILL the backend -> the link reports it is not connected (the kernel closes the
  sockets, so this is the close path);
* returned: start a backend on the same ports -> CONNECTED again; then until /odom flows again
  (re-subscribed);
* silent: a loopback proxy stops moving bytes without closing anything (a pulled cable) -> the
  link's keep-alive notices.

    python bench/recovery.py --trials 5

Last line: JSON (median and max of each, seconds).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable

from _common import emit

from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink
from tests.support.backend import start_backend
from tests.support.netfault import FaultProxy


def wait(predicate: Callable[[], bool], timeout: float) -> float | None:
    start = time.monotonic()
    while time.monotonic() - start < timeout:
        if predicate():
            return time.monotonic() - start
        time.sleep(0.005)
    return None


def summary(values: list[float | None]) -> dict:
    done = [v for v in values if v is not None]
    return {
        "median_s": round(statistics.median(done), 3) if done else None,
        "max_s": round(max(done), 3) if done else None,
        "failed": len(values) - len(done),
    }


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--trials", type=int, default=5)
    p.add_argument("--away", type=float, default=1.0, help="seconds the backend stays away (1.0)")
    args = p.parse_args()
    backend = start_backend()
    ports = ("--bridge-port", str(backend.bridge_port), "--api-port", str(backend.api_port))
    proxy = FaultProxy(backend.bridge_port)
    link = RosLink("127.0.0.1", backend.bridge_port)
    via_proxy = RosLink("127.0.0.1", proxy.port)
    killed: list[float | None] = []
    returned: list[float | None] = []
    resubscribed: list[float | None] = []
    silent: list[float | None] = []
    try:
        wait(lambda: link.state == CONNECTED and via_proxy.state == CONNECTED, 15)
        for _ in range(args.trials):
            proxy.freeze()  # a dead link: nothing closes, nothing moves
            silent.append(wait(lambda: via_proxy.state != CONNECTED, 10))
            proxy.thaw()
            wait(lambda: via_proxy.state == CONNECTED, 10)

            backend.proc.kill()
            killed.append(wait(lambda: link.state != CONNECTED, 10))
            backend.proc.wait()
            time.sleep(args.away)
            backend = start_backend(*ports)
            odom = link.telemetry.odom_count
            returned.append(wait(lambda: link.state == CONNECTED, 10))
            resubscribed.append(wait(lambda n=odom: link.telemetry.odom_count > n, 10))
            wait(lambda: via_proxy.state == CONNECTED, 10)
    finally:
        link.close()
        via_proxy.close()
        proxy.close()
        backend.stop()
    emit(
        {
            "bench": "recovery",
            "trials": args.trials,
            "killed_to_disconnected": summary(killed),
            "returned_to_connected": summary(returned),
            "connected_to_odom": summary(resubscribed),
            "silent_to_noticed": summary(silent),
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
