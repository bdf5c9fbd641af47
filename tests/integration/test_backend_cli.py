import signal
import socket
import subprocess
import sys

from ..support.backend import start_backend


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


def test_a_bad_flag_is_one_line_on_stderr_from_the_real_entry_point():
    """The in-process cases are in tests/unit/test_cli_args.py; this one runs the installed module."""
    r = subprocess.run(
        [sys.executable, "-m", "arbiter_backend.cli", "--max-records", "x"],
        capture_output=True,
        text=True,
        timeout=20,
    )
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.strip().splitlines() == [
        "arbiter-backend: argument --max-records: not a whole number: 'x' (see --help)"
    ]
