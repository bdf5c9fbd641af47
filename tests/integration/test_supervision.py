"""The embedded transport's workers (watchdog, simulator, topic monitor) and the fleet announcer, each made
to fail once (``ARBITER_FAULT``): each is restarted and says so in ``/api/health``, the error is logged
once, and the simulator's 50 Hz odometry is measured at its rate, never reported silent, throughout."""

import json
import os
import subprocess
import sys
import time

import httpx
import pytest

from ..support.backend import free_port, start_backend
from ..support.waits import wait_for

WORKERS = ("watchdog", "simulator", "topic-monitor", "fleet-announcer")
ODOM_HZ = 50.0
WINDOW = 3.0


def workers(api: str) -> dict[str, dict]:
    return {w["name"]: w for w in httpx.get(f"{api}/api/health", timeout=5).json().get("workers", [])}


def odometry(api: str) -> dict | None:
    return next(
        (t for t in httpx.get(f"{api}/api/topics", timeout=5).json()["topics"] if t["name"] == "/odom"), None
    )


def test_each_embedded_worker_made_to_fail_restarts_and_the_odometry_is_never_silent():
    faults = ",".join(f"{name}@2" for name in WORKERS)  # each 2 s after it started
    # no router at that endpoint: the announcer runs all the same (the link is retried in the background)
    backend = start_backend(
        "--zenoh",
        f"tcp/127.0.0.1:{free_port()}",
        "--topics-window",
        str(WINDOW),
        env={"ARBITER_FAULT": faults},
    )
    seen: list[tuple[str, float | None]] = []

    def watch(seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            row = odometry(backend.api)
            if row is not None:
                seen.append((row["state"], row["rate_hz"]))
            time.sleep(0.05)

    def all_restarted() -> bool:
        watch(0.2)
        w = workers(backend.api)
        return all(w.get(n, {}).get("restarts") == 1 and w[n]["state"] == "running" for n in WORKERS)

    try:
        assert wait_for(all_restarted, 20), workers(backend.api)
        watch(WINDOW)  # a whole window after the last
        w = workers(backend.api)
        for name in WORKERS:
            assert w[name]["last_error"] == {"type": "InjectedFault", "message": f"ARBITER_FAULT={name}"}, w
        assert not [s for s in seen if s[0] == "silent"], seen
        state, rate = seen[-1]
        assert state == "ok" and rate is not None and abs(rate - ODOM_HZ) <= 0.1 * ODOM_HZ, seen[-20:]
        assert backend.proc.poll() is None
    finally:
        assert backend.stop() == 0
    err = backend.proc.stderr.read() if backend.proc.stderr else ""
    for name in WORKERS:
        assert err.count(f"{name} failed, restarting") == 1, err


def test_a_malformed_fault_is_refused_in_one_line():
    r = subprocess.run(
        [sys.executable, "-m", "arbiter_backend.cli", "--api-port", "0", "--bridge-port", "0"],
        env={**os.environ, "ARBITER_FAULT": "topic-monitor@soon"},
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert r.returncode == 2, r
    assert "ARBITER_FAULT: bad item 'topic-monitor@soon'" in r.stderr and len(r.stderr.splitlines()) == 1, (
        r.stderr
    )


@pytest.mark.slow  # the hold must outlast the topics payload's 5 s period
def test_a_fleet_console_reads_monitor_restarted_while_the_robots_monitor_is_down():
    """The monitor held down through five backoffs (about 6 s: longer than the topics payload's period):
    the robot's row on a real fleet console says "monitor restarted: …", a warning, not a silent topic;
    /api/health says the monitor runs again after its sixth failure."""
    import zenoh

    from arbiter_tui.fleet.client import ConsoleSettings, FleetClient
    from arbiter_tui.fleet.rows import FleetModel

    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    config = {
        "mode": "router",
        "listen": {"endpoints": [endpoint]},
        "scouting": {"multicast": {"enabled": False}},
    }
    router = zenoh.open(zenoh.Config.from_json5(json.dumps(config)))
    backend = start_backend(
        "--no-bridge", "--zenoh", endpoint, "--robot-name", "held", env={"ARBITER_FAULT": "topic-monitor*6"}
    )
    console = FleetClient(ConsoleSettings(connect=(endpoint,)), FleetModel(stale_after=3.0))
    try:
        console.open(connect_timeout_ms=5000)

        def row():
            return next((r for r in console.view().rows if r.name == "held"), None)

        why = "monitor restarted: InjectedFault: ARBITER_FAULT=topic-monitor"
        assert wait_for(lambda: (r := row()) is not None and r.worst_topic == why, 20), row()
        assert row().worst_health == "unknown" and row().severity == 1  # WARN
        assert wait_for(lambda: workers(backend.api).get("topic-monitor", {}).get("state") == "running", 20)
        assert workers(backend.api)["topic-monitor"]["restarts"] == 6
    finally:
        console.close()
        backend.stop()
        router.close()
