import signal
import socket
import subprocess
import sys

from .conftest import start_backend


def test_sigterm_stops_cleanly():
    b = start_backend()
    b.proc.send_signal(signal.SIGTERM)
    out, err = b.proc.communicate(timeout=10)
    assert b.proc.returncode == 0
    assert "stopped" in out
    assert "Traceback" not in err


def test_sigint_stops_cleanly():
    b = start_backend()
    b.proc.send_signal(signal.SIGINT)
    b.proc.communicate(timeout=10)
    assert b.proc.returncode == 0


def test_busy_port_is_a_one_line_error_with_exit_code_2():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        r = subprocess.run(
            [sys.executable, "-m", "arbiter_backend.cli", "--bridge-port", str(port), "--api-port", "0"],
            capture_output=True,
            text=True,
            timeout=20,
        )
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert "cannot listen" in r.stderr


def test_flags_reach_the_tracker_and_bad_values_are_rejected():
    import httpx

    b = start_backend("--deploy-mode", "pi", "--no-sim", "--max-records", "5")
    try:
        body = httpx.get(f"{b.api}/api/latency").json()
        assert body["deploy_mode"] == "pi"
        assert httpx.get(f"{b.api}/api/latency?limit=6").status_code == 400  # above max-records
    finally:
        assert b.stop() == 0
    for bad in (
        ["--bridge-port", "99999"],
        ["--cmd-timeout", "-1"],
        ["--max-records", "x"],
        ["--cmd-timeout", "nan"],
        ["--max-command-age", "-5"],
        ["--max-linear-accel", "0"],
        ["--max-angular", "inf"],
        ["--measured-type", "pose"],
        ["--ros-args", "-p", "x:=1"],  # ROS arguments without --transport ros
        ["--unknown-flag"],
    ):
        r = subprocess.run(
            [sys.executable, "-m", "arbiter_backend.cli", *bad], capture_output=True, text=True, timeout=20
        )
        assert r.returncode == 2 and "Traceback" not in r.stderr, bad
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("arbiter-backend: "), (bad, r.stderr)


def test_help_mentions_every_flag():
    r = subprocess.run(
        [sys.executable, "-m", "arbiter_backend.cli", "--help"], capture_output=True, text=True
    )
    for flag in (
        "--host",
        "--bridge-port",
        "--api-port",
        "--deploy-mode",
        "--no-sim",
        "--no-bridge",
        "--max-records",
        "--cmd-timeout",
        "--max-command-age",
        "--max-linear-accel",
        "--max-angular-accel",
        "--allow-remote",
        "--token-file",
        "--log-file",
    ):
        assert flag in r.stdout
