#!/usr/bin/env python
"""The same controller console-side and robot-side, on the same mission, at 0 and 200 ms of one-way link
latency (issue 35's closing table).

Console-side: ``compare``'s modelled link (``run_one`` with a ``LinkModel`` of that latency each way:
commands and odometry each that late), in simulated time. Robot-side: ``arbiter-backend --autonomy`` runs the
controller on the robot's own odometry and the console observes it (``--observe``) through a proxy
that delays each direction of its rosbridge connection by that latency (tests/support/delayproxy.py),
in real time; the figures are the console's observed run. The robot-side loop has no link in it, so
the latency can change only what the console sees, not how the robot drives.

    python bench/robot_side.py --algorithms stanley,pure_pursuit --mission corner --latency 0,200
"""

from __future__ import annotations

import argparse
import json
import sys
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from arbiter_core.linkmodel import LinkModel  # noqa: E402
from arbiter_tui.analytics.runs import COMPLETED  # noqa: E402
from arbiter_tui.link.base import CONNECTED  # noqa: E402
from arbiter_tui.link.rosbridge import RosLink  # noqa: E402
from arbiter_tui.session.compare import run_one  # noqa: E402
from arbiter_tui.session.robot import RobotSession  # noqa: E402
from arbiter_tui.session.settings import Settings  # noqa: E402
from tests.support.backend import start_backend  # noqa: E402
from tests.support.delayproxy import DelayProxy, Delays  # noqa: E402
from tests.support.waits import wait_for  # noqa: E402


def robot_side(algorithm: str, mission: str, latency_ms: float) -> dict:
    backend = start_backend("--autonomy")
    proxy = DelayProxy(backend.bridge_port, Delays(latency_ms, latency_ms))
    settings = Settings(handle_signals=False, observe=True, observe_label=algorithm,
                        cmd_topic="/cmd_vel_measured")  # fmt: skip
    link = RosLink("127.0.0.1", proxy.port)
    session = RobotSession(settings, link)
    try:
        assert wait_for(lambda: link.state == CONNECTED, 20), "no connection"
        assert wait_for(lambda: link.telemetry.odom_count > 0, 10), "no odometry"
        body = json.dumps({"algorithm": algorithm, "mission": mission}).encode()
        urllib.request.urlopen(urllib.request.Request(f"{backend.api}/api/autonomy", body, method="POST"))
        done = lambda: [r for r in session.store.runs() if r.outcome == COMPLETED]  # noqa: E731
        assert wait_for(lambda: done(), 120), session.store.runs()
        (run,) = done()
        return {"xte_mean_m": run.tracking.xte_mean_m, "xte_max_m": run.tracking.xte_max_m,
                "time_s": run.time_s, "path_m": run.stats.totalPathLength}  # fmt: skip
    finally:
        link.close()
        proxy.close()
        backend.stop()


def console_side(algorithm: str, mission: str, latency_ms: float) -> dict:
    delay = latency_ms / 1000.0  # each way, as the proxy delays the robot-side rows
    r = run_one(algorithm, mission, link_model=LinkModel(latency_s=delay, odom_delay_s=delay))
    time_s = r.time_s if r.completed else float("nan")
    return {"xte_mean_m": r.tracking.xte_mean_m, "xte_max_m": r.tracking.xte_max_m, "time_s": time_s,
            "path_m": r.stats.totalPathLength}  # fmt: skip


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--algorithms", default="stanley,pure_pursuit")
    p.add_argument("--mission", default="corner")
    p.add_argument("--latency", default="0,200", help="one-way ms, comma-separated")
    a = p.parse_args()
    rows = []
    for algorithm in a.algorithms.split(","):
        for latency in (float(x) for x in a.latency.split(",")):
            for side, fn in (("console", console_side), ("robot", robot_side)):
                rows.append({"algorithm": algorithm, "latency_ms": latency, "side": side,
                             **fn(algorithm, a.mission, latency)})  # fmt: skip
                r = rows[-1]
                print(f"{algorithm:14} {latency:5.0f} ms  {side:7}  avg e_xt {r['xte_mean_m'] * 1000:6.1f} mm"
                      f"  max {r['xte_max_m'] * 1000:6.1f} mm  time {r['time_s']:5.2f} s"
                      f"  path {r['path_m']:.2f} m", flush=True)  # fmt: skip
    print(json.dumps({"bench": "robot_side", "mission": a.mission, "rows": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
