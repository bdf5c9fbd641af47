"""Run the stock rosbridge_server's own WebSocket tests, unmodified, against our endpoint.

The tests live in RobotWebTools/rosbridge_suite (ros2 branch), ``rosbridge_server/test/websocket/``.
Each starts its own rosbridge_websocket through launch_testing and asks
``/rosbridge_websocket/get_parameters`` for ``actual_port``. This harness stubs only the launch
step: it starts a fresh ``arbiter-backend --transport ros`` for every run (a fresh endpoint is where
discovery races show) with its bridge node renamed ``rosbridge_websocket``; our bridge node declares
``actual_port`` as rosbridge's does, so the tests find the port through the graph, unmodified (and
wait, as against the stock server, until the two processes have discovered each other).
Needs the ``[ros]`` extra (rclpy, std_msgs, rcl_interfaces) and autobahn/twisted (roslibpy's).

    git clone -b ros2 https://github.com/RobotWebTools/rosbridge_suite /tmp/rosbridge_suite
    python bench/rosbridge_stock.py --suite /tmp/rosbridge_suite --runs 5

Prints one line per run and a table of passes; exits non-zero when a run failed.
"""

from __future__ import annotations

import argparse
import os
import random
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tests.support.backend import start_backend  # noqa: E402

RENAME = "arbiter_bridge:__node:=rosbridge_websocket"  # where the tests ask for actual_port
DEFAULT_TESTS = ("smoke", "multiple_subscribers", "best_effort_publisher", "transient_local_publisher")

# Runs in the child: stub launch/launch_ros/launch_testing (only used to start the stock server), point
# common.get_server_port at our port, then run the test file's TestCase with unittest.
CHILD = r"""
import importlib.util, sys, types, unittest
test_dir, test_file = sys.argv[1], sys.argv[2]
for name in ("launch", "launch.actions", "launch_ros", "launch_ros.actions", "launch_testing",
             "launch_testing.actions"):
    sys.modules[name] = types.ModuleType(name)
sys.modules["launch_testing.actions"].ReadyToTest = object
sys.modules["launch"].LaunchDescription = object  # annotations, evaluated when common is imported
sys.path.insert(0, test_dir)
spec = importlib.util.spec_from_file_location("stock_test", test_file)
module = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
suite = unittest.defaultTestLoader.loadTestsFromModule(module)
result = unittest.TextTestRunner(verbosity=0).run(suite)
sys.exit(0 if result.wasSuccessful() and result.testsRun else 1)
"""


def run_one(
    test_dir: Path, name: str, timeout: float, env: dict[str, str], log: Path | None
) -> tuple[bool, float, str]:
    extra = ("--log-level", "DEBUG", "--log-file", str(log)) if log else ()
    backend = start_backend("--transport", "ros", *extra, "--ros-args", "-r", RENAME, timeout=30, env=env)
    started = time.monotonic()
    try:
        proc = subprocess.run(
            [sys.executable, "-c", CHILD, str(test_dir), str(test_dir / f"{name}.test.py")],
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
        )
        ok, tail = proc.returncode == 0, (proc.stderr or proc.stdout).strip().splitlines()[-3:]
    except subprocess.TimeoutExpired as exc:
        ok, tail = False, [f"timed out after {timeout:.0f} s", *(str(exc.stderr or "").splitlines()[-2:])]
    finally:
        backend.stop()
    return ok, time.monotonic() - started, " | ".join(tail)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", type=Path, required=True, help="a rosbridge_suite checkout (ros2 branch)")
    ap.add_argument("--runs", type=int, default=5, help="consecutive runs of each test (default 5)")
    ap.add_argument("--tests", default=",".join(DEFAULT_TESTS), help="comma-separated test names")
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds before a run counts as failed")
    ap.add_argument("--log-dir", type=Path, help="keep each run's backend log (DEBUG) here")
    args = ap.parse_args(argv)
    test_dir = args.suite / "rosbridge_server" / "test" / "websocket"
    if not (test_dir / "common.py").is_file():
        ap.error(f"{test_dir} has no common.py: is --suite a rosbridge_suite checkout (ros2 branch)?")
    env = {
        **os.environ,
        "ROS_DOMAIN_ID": str(random.Random(os.getpid()).randint(101, 200)),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "PYTHONUNBUFFERED": "1",
    }
    if args.log_dir:
        args.log_dir.mkdir(parents=True, exist_ok=True)
    passed: dict[str, int] = {}
    for name in args.tests.split(","):
        passed[name] = 0
        for run in range(1, args.runs + 1):
            log = args.log_dir / f"{name}-{run}.log" if args.log_dir else None
            ok, took, tail = run_one(test_dir, name, args.timeout, env, log)
            passed[name] += ok
            verdict = "pass" if ok else f"FAIL  {tail}"
            print(f"{name:28} run {run}: {took:5.1f} s {verdict}", flush=True)
    print()
    print(f"{'test':28} passed")
    for name, n in passed.items():
        print(f"{name:28} {n}/{args.runs}")
    return 0 if all(n == args.runs for n in passed.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
