"""Run the stock rosbridge_server's own WebSocket tests, unmodified, against our endpoint.

The tests live in RobotWebTools/rosbridge_suite (ros2 branch), ``rosbridge_server/test/websocket/``.
Each starts its own rosbridge_websocket through launch_testing and asks
``/rosbridge_websocket/get_parameters`` for ``actual_port``. This harness stubs only the launch
step: it starts a fresh ``arbiter-backend --transport ros`` for every run (a fresh endpoint is where
discovery races show) with its bridge node renamed ``rosbridge_websocket``; our bridge node declares
``actual_port`` as rosbridge's does, so the tests find the port through the graph, unmodified (and
wait, as against the stock server, until the two processes have discovered each other).
Needs the ``[ros]`` extra (rclpy, std_msgs, rcl_interfaces, std_srvs) and autobahn/twisted (roslibpy's).

The three action tests (advertise_action, advertise_action_feedback, send_action_goal) import
``example_interfaces``, which has no wheel on PyPI: where it is installed in the Python that runs this
(a ROS install, or a venv it was built into from ros2/example_interfaces with the rosidl and ament
wheels, cmake and ninja) they run unmodified. Else ``--fibonacci-from test_msgs`` runs them on a copy
whose only change is that package name (``test_msgs/action/Fibonacci``, a wheel, is the same action:
``int32 order`` / ``int32[] sequence`` / ``int32[] sequence``); the table marks them ``(test_msgs)``.

    git clone -b ros2 https://github.com/RobotWebTools/rosbridge_suite /tmp/rosbridge_suite
    python bench/rosbridge_stock.py --suite /tmp/rosbridge_suite --runs 5
    python bench/rosbridge_stock.py --suite /tmp/rosbridge_suite --tests all --fibonacci-from test_msgs

``--one-server`` runs the tests in sequence against **one** backend, as a robot's server lives
(``--runs`` sweeps of every test in a row), and ``--stress N`` runs ``stress-ng --cpu N`` beside it
all (Debian's stress-ng):

    python bench/rosbridge_stock.py --suite /tmp/rosbridge_suite --tests all --fibonacci-from test_msgs \
        --one-server --runs 5 --stress 2

Prints one line per run and a table of passes; exits non-zero when a run failed.
"""

from __future__ import annotations

import argparse
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tests.support.backend import start_backend  # noqa: E402

RENAME = "arbiter_bridge:__node:=rosbridge_websocket"  # where the tests ask for actual_port
DEFAULT_TESTS = (
    "smoke",
    "multiple_subscribers",
    "best_effort_publisher",
    "transient_local_publisher",
    "advertise_service",
    "advertise_service_duplicate",
    "call_service",
)
ACTION_TESTS = ("advertise_action", "advertise_action_feedback", "send_action_goal")

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


def start(env: dict[str, str], log: Path | None):  # -> tests.support.backend's Backend
    extra = ("--log-level", "DEBUG", "--log-file", str(log)) if log else ()
    return start_backend("--transport", "ros", *extra, "--ros-args", "-r", RENAME, timeout=30, env=env)


def run_one(
    test_dir: Path, name: str, timeout: float, env: dict[str, str], log: Path | None, shared=None
) -> tuple[bool, float, str]:
    """One run of one test file: against ``shared`` (a running backend), else a fresh backend."""
    backend = shared if shared is not None else start(env, log)
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
        if shared is None:
            backend.stop()
    return ok, time.monotonic() - started, " | ".join(tail)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", type=Path, required=True, help="a rosbridge_suite checkout (ros2 branch)")
    ap.add_argument("--runs", type=int, default=5, help="consecutive runs of each test (default 5)")
    ap.add_argument("--tests", default=",".join(DEFAULT_TESTS), help="comma-separated test names")
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds before a run counts as failed")
    ap.add_argument("--log-dir", type=Path, help="keep each run's backend log (DEBUG) here")
    ap.add_argument(
        "--fibonacci-from",
        metavar="PKG",
        help="run the action tests on a copy importing Fibonacci from PKG instead of example_interfaces",
    )
    ap.add_argument("--one-server", action="store_true",
                    help="every run against one backend, in sweeps of every test (as a robot's server lives)")
    ap.add_argument("--stress", type=int, default=0, metavar="N", help="stress-ng --cpu N beside it all")
    args = ap.parse_args(argv)
    test_dir = args.suite / "rosbridge_server" / "test" / "websocket"
    if not (test_dir / "common.py").is_file():
        ap.error(f"{test_dir} has no common.py: is --suite a rosbridge_suite checkout (ros2 branch)?")
    names = args.tests.split(",")
    if names == ["all"]:
        names = sorted({*DEFAULT_TESTS, *ACTION_TESTS, "multiple_subscribers_raw"})
    swapped_dir = None
    if args.fibonacci_from:
        swapped_dir = Path(tempfile.mkdtemp(prefix="rosbridge_stock_"))
        shutil.copytree(test_dir, swapped_dir, dirs_exist_ok=True)
        for name in ACTION_TESTS:
            f = swapped_dir / f"{name}.test.py"
            f.write_text(f.read_text().replace("example_interfaces", args.fibonacci_from))
    env = {
        **os.environ,
        "ROS_DOMAIN_ID": str(random.Random(os.getpid()).randint(101, 200)),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "PYTHONUNBUFFERED": "1",
    }
    if args.log_dir:
        args.log_dir.mkdir(parents=True, exist_ok=True)
    passed: dict[str, int] = {}
    labels = {}
    for name in names:
        swapped = swapped_dir is not None and name in ACTION_TESTS
        label = f"{name} ({args.fibonacci_from})" if swapped else name
        labels[name] = (label, swapped_dir if swapped else test_dir)
        passed[labels[name][0]] = 0
    stress = None
    if args.stress:
        stress = subprocess.Popen(["stress-ng", "--cpu", str(args.stress), "--quiet"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    shared_log = args.log_dir / "one-server.log" if args.log_dir else None
    shared = start(env, shared_log) if args.one_server else None
    # fresh servers: each test's runs in a row; one server: sweeps of every test in a row
    order = ([(run, name) for run in range(1, args.runs + 1) for name in names] if shared
             else [(run, name) for name in names for run in range(1, args.runs + 1)])  # fmt: skip
    try:
        for run, name in order:
            label, where = labels[name]
            log = args.log_dir / f"{name}-{run}.log" if args.log_dir and shared is None else None
            ok, took, tail = run_one(where, name, args.timeout, env, log, shared)
            passed[label] += ok
            verdict = "pass" if ok else f"FAIL  {tail}"
            print(f"{label:40} run {run}: {took:5.1f} s {verdict}", flush=True)
    finally:
        if shared is not None:
            shared.stop()
        if stress is not None:
            stress.terminate()
            stress.wait()
    mode = "one server" if shared else "a fresh server each run"
    print(f"\n{mode}{f', beside stress-ng --cpu {args.stress}' if args.stress else ', idle'}")
    print()
    print(f"{'test':40} passed")
    for label, n in passed.items():
        print(f"{label:40} {n}/{args.runs}")
    return 0 if all(n == args.runs for n in passed.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
