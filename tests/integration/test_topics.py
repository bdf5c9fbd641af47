"""``GET /api/topics`` on the embedded backend, and ``arbiter-tui topics`` against it (real processes)."""

import asyncio
import json
import subprocess
import sys

import aiohttp
import httpx
import pytest

from ..support.backend import free_port, start_backend, wait_for


@pytest.fixture(scope="module")
def backend():
    b = start_backend("--topics-window", "2")
    yield b
    b.stop()


def topics(b) -> dict[str, dict]:
    body = httpx.get(f"{b.api}/api/topics", timeout=5).json()
    assert body["window_s"] == 2.0
    return {t["name"]: t for t in body["topics"]}


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "arbiter_tui.cli", "topics", *args], capture_output=True, text=True, timeout=30
    )


def test_the_simulators_odometry_is_measured_and_a_clients_topic_appears(backend):
    assert wait_for(lambda: topics(backend)["/odom"]["total"] > topics(backend)["/odom"]["count"], 10)
    odom = topics(backend)["/odom"]
    assert odom["state"] == "ok" and odom["rate_hz"] == pytest.approx(50.0, rel=0.05)
    assert odom["stamped"] and 0 <= odom["delay_mean_ms"] < 50  # stamped when simulated, sent at once
    assert odom["publishers"] == 1 and odom["mean_size_bytes"] > 100
    assert odom["bandwidth_bps"] == pytest.approx(odom["rate_hz"] * odom["mean_size_bytes"], rel=0.05)
    assert topics(backend)["/stamped_cmd_vel"]["state"] == "waiting"

    async def publish_chatter() -> None:
        async with aiohttp.ClientSession() as s, s.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}") as ws:
            await ws.send_json({"op": "advertise", "topic": "/chatter", "type": "std_msgs/String"})
            for i in range(20):
                await ws.send_json({"op": "publish", "topic": "/chatter", "msg": {"data": f"hello {i}"}})
            # a stamp whose nanoseconds are out of range: counted, not fatal
            await ws.send_json({"op": "advertise", "topic": "/bad_odom", "type": "nav_msgs/Odometry"})
            bad = {"header": {"stamp": {"sec": 1, "nanosec": 2_000_000_000}, "frame_id": "odom"}}
            await ws.send_json({"op": "publish", "topic": "/bad_odom", "msg": bad})
            assert wait_for(lambda: topics(backend).get("/chatter", {}).get("total") == 20, 10)
            chatter = topics(backend)["/chatter"]
            assert chatter["publishers"] == 1 and chatter["type"] == "std_msgs/msg/String"
            assert not chatter["stamped"] and chatter["delay_mean_ms"] is None
            assert wait_for(lambda: topics(backend).get("/bad_odom", {}).get("malformed_stamps") == 1, 10)
            assert topics(backend)["/bad_odom"]["delay_mean_ms"] is None

    asyncio.run(publish_chatter())
    # the client went away: its publisher with it; the rows stay, quiet (20 messages in a burst: no
    # steady rhythm that stopped, so not silent)
    assert wait_for(lambda: topics(backend)["/chatter"]["state"] == "quiet", 10)
    assert topics(backend)["/chatter"]["publishers"] == 0


def test_a_command_topic_that_stops_is_quiet_not_silent(backend):
    """/stamped_cmd_vel is on the graph from the backend's start and waits for its first message: a key
    held for longer than the window (10 Hz for 3 s) and released leaves it quiet, never silent."""
    import time

    assert wait_for(lambda: topics(backend)["/odom"]["total"] > topics(backend)["/odom"]["count"], 10)

    async def hold() -> None:
        async with aiohttp.ClientSession() as s, s.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}") as ws:
            await ws.send_json({"op": "advertise", "topic": "/stamped_cmd_vel", "type": "std_msgs/String"})
            for _ in range(30):  # not envelopes: the tracker rejects them, the monitor counts them
                await ws.send_json({"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": "held"}})
                await asyncio.sleep(0.1)

    asyncio.run(hold())
    seen, deadline = [], time.monotonic() + 4.0  # the window (2 s) empties, and more
    while time.monotonic() < deadline:
        seen.append(topics(backend)["/stamped_cmd_vel"]["state"])
        time.sleep(0.1)
    assert "silent" not in seen and seen[-1] == "quiet", seen
    # nothing in the window, and still an age: how long ago its last message came (4 s and more)
    quiet = topics(backend)["/stamped_cmd_vel"]
    assert quiet["count"] == 0 and quiet["age_ms"] >= 4000.0, quiet


def test_the_first_answer_already_holds_each_topics_rate_over_the_time_before_it():
    """Nobody asked this backend anything for 4 s: its first answer has /odom's rate once a second since
    it started (the console's plot covers the last minute the moment its topics screen opens)."""
    import time

    fresh = start_backend("--topics-window", "2")
    try:
        time.sleep(4.0)
        odom = topics(fresh)["/odom"]
        history = odom["rate_history"]
        assert 3 <= len(history) <= 6, history
        assert history[-1] == pytest.approx(50.0, rel=0.1), history
        assert all(r is None or r == pytest.approx(50.0, rel=0.1) for r in history), history
        assert {"rate_hz", "count", "state", "usual_rate_hz"} <= set(odom)  # the fields before it, kept
    finally:
        fresh.stop()


def test_cli_prints_the_table_json_and_checks_expectations(backend):
    assert wait_for(lambda: (topics(backend)["/odom"]["rate_hz"] or 0) > 40, 10)
    table = cli("--tracker", backend.api)
    assert table.returncode == 0, table.stderr
    assert table.stdout.splitlines()[0].split()[:3] == ["topic", "type", "state"]
    assert any(line.startswith("/odom ") and " ok " in line for line in table.stdout.splitlines())
    as_json = cli("--tracker", backend.api, "--json")
    assert {t["name"] for t in json.loads(as_json.stdout)["topics"]} >= {"/odom", "/stamped_cmd_vel"}
    ok = cli("--tracker", backend.api, "--expect", "/odom>=40")
    assert ok.returncode == 0 and ok.stderr == ""
    unmet = cli("--tracker", backend.api, "--expect", "/odom>=400,/scan>=9.5")
    assert unmet.returncode == 1
    lines = unmet.stderr.splitlines()
    assert len(lines) == 2 and lines[1] == "arbiter-tui topics: /scan: not on the graph (expected >= 9.5 Hz)"
    assert unmet.stderr.splitlines()[0].startswith("arbiter-tui topics: /odom: ")
    assert "expected >= 400 Hz" in unmet.stderr.splitlines()[0]


def test_cli_bad_arguments_and_a_dead_backend_are_one_line_errors():
    bad = cli("--expect", "odom>5")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "TOPIC>=HZ" in bad.stderr
    dead = cli("--tracker", f"http://127.0.0.1:{free_port()}", "--timeout", "2")
    assert dead.returncode == 3 and dead.stderr.count("\n") == 1 and "cannot connect" in dead.stderr
    assert "Traceback" not in dead.stderr + bad.stderr
