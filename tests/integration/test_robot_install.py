"""The robot's install (issue 48, item 6): ``pip install ./robot`` into a fresh environment installs the
backend alone -- no Textual, roslibpy, Twisted, httpx, mcap or rosbags -- and that backend runs: it
binds, serves the API, and refuses ``--transport ros`` without rclpy in one line; ``--zenoh`` without Zenoh
names the robot's own ``[fleet]`` extra (issue 54, item 5), never the console's package."""

import subprocess
import sys
import venv
from pathlib import Path

import httpx
import pytest

from arbiter_core.listening import parse_listening

ROOT = Path(__file__).resolve().parents[2]
CONSOLE_ONLY = ("textual", "textual_plot", "roslibpy", "twisted", "httpx", "mcap", "rosbags", "arbiter_tui")


@pytest.fixture(scope="module")
def robot_env(tmp_path_factory) -> Path:
    env = tmp_path_factory.mktemp("robot") / "venv"
    venv.create(env, with_pip=True)
    python = env / "bin" / "python"
    done = subprocess.run(
        [str(python), "-m", "pip", "install", "-q", "--disable-pip-version-check", str(ROOT / "robot")],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return python


def test_the_robot_install_carries_no_console_code(robot_env):
    probe = f"import importlib.util as u; print(' '.join(m for m in {CONSOLE_ONLY!r} if u.find_spec(m)))"
    found = subprocess.run([str(robot_env), "-c", probe], capture_output=True, text=True, cwd="/", timeout=60)
    assert found.returncode == 0 and found.stdout.split() == [], found.stdout
    version = subprocess.run([str(robot_env.parent / "arbiter-backend"), "--version"], capture_output=True,
                             text=True, cwd="/", timeout=60)  # fmt: skip
    assert version.stdout.strip() == "arbiter-backend 0.1.0"  # from the robot's distribution's metadata


def test_the_robot_installs_backend_runs(robot_env):
    proc = subprocess.Popen(
        [str(robot_env.parent / "arbiter-backend"), "--bridge-port", "0", "--api-port", "0", "--autonomy"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd="/",
    )  # fmt: skip
    try:
        found = None
        for _ in range(50):
            found = parse_listening(proc.stdout.readline())
            if found is not None:
                break
        assert found is not None, proc.stderr.read() if proc.poll() is not None else "no listening line"
        health = httpx.get(f"http://127.0.0.1:{found.api_port}/api/health", timeout=5).json()
        assert health["status"] == "ok" and health["node"] == "latency_tracker"
        autonomy = httpx.get(f"http://127.0.0.1:{found.api_port}/api/autonomy", timeout=5).json()
        assert autonomy["state"] == "idle"
    finally:
        proc.terminate()
        proc.wait(10)
    if sys.version_info[:2] not in ((3, 11), (3, 12)) or "rclpy" in sys.modules:
        return
    refused = subprocess.run([str(robot_env.parent / "arbiter-backend"), "--transport", "ros"],
                             capture_output=True, text=True, cwd="/", timeout=60)  # fmt: skip
    assert refused.returncode != 0 and "rclpy is not importable" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1


def test_the_robots_backend_names_the_robots_fleet_extra(robot_env):
    probe = "import importlib.metadata as m; print(m.metadata('arbiter-backend').get_all('Provides-Extra'))"
    extras = subprocess.run([str(robot_env), "-c", probe], capture_output=True, text=True, cwd="/",
                            timeout=60)  # fmt: skip
    assert "'fleet'" in extras.stdout, extras.stdout + extras.stderr
    refused = subprocess.run([str(robot_env.parent / "arbiter-backend"), "--zenoh", "tcp/127.0.0.1:7447"],
                             capture_output=True, text=True, cwd="/", timeout=60)  # fmt: skip
    assert refused.returncode == 2 and "--zenoh needs eclipse-zenoh" in refused.stderr, refused.stderr
    assert "pip install './robot[fleet]'" in refused.stderr, refused.stderr
    assert "arbiter-tui" not in refused.stderr, refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1
