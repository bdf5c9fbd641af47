"""What the backend costs beside a graph shaped like a real robot's, against today's small graph.

``arbiter-backend --transport ros`` (the simulated base, the tracker, the relay, the topic monitor
watching everything) on a ROS domain of its own, in phases alternated ``--repeat`` times, each for
``--seconds`` after ``--warmup``:

- ``small``: the backend alone (its own topics: /odom, /cmd_vel_measured, /latency_report, ...);
- ``robot``: beside ``tests/support/robotgraph.py`` (a Nav2-shaped bringup: lifecycle nodes, seven
  actions, introspected services, Nav2's topics, 100 hub topics, a second robot);
- ``robot 300``: the same graph with 300 hub topics.

CPU is the backend process's user + system time (/proc) over the phase, as a % of one core; the graph
runs in its own process and is not counted. Each phase also prints how many topics the backend listed
and its workers' states (``/api/health``), so a run shows the graph was seen whole, and in the graph
phases how far each steadily flowing topic's measured rate is from its truth (the graph's own publish
times over the monitor's window: ``tests/support/truth.py``): the median and worst relative error, and
a few topics' rates side by side.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from _common import emit  # noqa: E402
from topics import measure  # noqa: E402

from tests.support.backend import get_json, start_backend  # noqa: E402
from tests.support.truth import steady  # noqa: E402

GRAPH = ROOT / "tests" / "support" / "robotgraph.py"
PHASES = {"small": None, "robot": 100, "robot 300": 300}
SHOWN = ("/odom", "/imu/data", "/joint_states", "/scan", "/local_plan", "/diagnostics", "/robot2/odom")


def rates(graph: subprocess.Popen[str], api: str) -> dict[str, object]:
    """Measured against true rates, for every topic that flowed through the whole window."""
    answer = get_json(f"{api}/api/topics")
    asked_at = time.monotonic()
    assert graph.stdin is not None and graph.stdout is not None
    graph.stdin.write("dump\n")
    graph.stdin.flush()
    line = graph.stdout.readline()
    while not line.startswith("{"):  # "ready 2" came first
        line = graph.stdout.readline()
    sent = json.loads(line)
    window = answer["window_s"]
    got = {t["name"]: t for t in answer["topics"]}
    errors, shown = [], {}
    for name, times in sent["times"].items():
        truth = steady(times, asked_at - window, asked_at)
        measured = (got.get(name) or {}).get("rate_hz")
        if truth is None or measured is None:
            continue
        errors.append(abs(measured - truth) / truth)
        if name in SHOWN:
            shown[name] = (round(truth, 2), round(measured, 2))
    return {
        "topics_compared": len(errors),
        "median_rel_error": round(statistics.median(errors), 4) if errors else None,
        "max_rel_error": round(max(errors), 4) if errors else None,
        "shown": shown,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=20.0, help="length of each phase (default 20)")
    ap.add_argument("--repeat", type=int, default=3, help="rounds of the three phases (default 3)")
    ap.add_argument("--warmup", type=float, default=8.0, help="seconds before each phase is measured")
    args = ap.parse_args()
    env = {**os.environ, "ROS_DOMAIN_ID": str(random.Random(os.getpid()).randint(101, 200)),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONUNBUFFERED": "1"}  # fmt: skip
    os.environ.update(env)
    cpu: dict[str, list[float]] = {k: [] for k in PHASES}
    for _ in range(args.repeat):
        for name, hub in PHASES.items():
            graph = None
            if hub is not None:
                graph = subprocess.Popen(
                    [sys.executable, str(GRAPH), "--hub", str(hub), "--wave2-after", "1"],
                    stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env,
                )  # fmt: skip
                assert graph.stdout is not None and graph.stdout.readline().strip() == "ready 1"
            backend = start_backend("--transport", "ros", timeout=30, env=env)
            try:
                time.sleep(args.warmup)  # the graph's second wave up and every topic subscribed
                cpu[name].append(measure(backend.proc.pid, args.seconds))
                listed = len(get_json(f"{backend.api}/api/topics")["topics"])
                workers = get_json(f"{backend.api}/api/health").get("workers", [])
                states = sorted({w.get("state", "?") for w in workers})
                print(
                    f"{name}: {cpu[name][-1]:.1f} % of a core, {listed} topics, workers {states}", flush=True
                )
                if graph is not None:
                    print(json.dumps({"phase": name, "rates": rates(graph, backend.api)}), flush=True)
            finally:
                backend.stop()
                if graph is not None:
                    graph.kill()
                    graph.wait(5)
    med = {k: statistics.median(v) for k, v in cpu.items()}
    emit(
        {
            "bench": "robot_graph",
            "seconds": args.seconds,
            "repeat": args.repeat,
            **{f"{k.replace(' ', '_')}_cpu_pct": round(v, 2) for k, v in med.items()},
            "robot_over_small": round(med["robot"] / med["small"], 2),
            "robot300_over_small": round(med["robot 300"] / med["small"], 2),
        }
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
