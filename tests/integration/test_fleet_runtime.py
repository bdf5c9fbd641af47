"""The fleet console's Zenoh runtime: its accept runtime handed over to its rx runtime (each packet of a
link accepted by the console's router was woken through an accept thread: a thread switch per payload,
1-1.5 % of a core at 500 robots, ``bench/fleet.py``); a ``ZENOH_RUNTIME`` of the user's is kept."""

import json
import os
import subprocess
import sys

from ..support.backend import free_port

CONSOLE = """
import json, os, sys, time, zenoh
from arbiter_tui.fleet.client import ConsoleSettings, FleetClient
c = FleetClient(ConsoleSettings(listen=(sys.argv[1],)))
c.open()
cfg = {"mode": "client", "connect": {"endpoints": [sys.argv[1]]}}
cfg["scouting"] = {"multicast": {"enabled": False}}
robot = zenoh.open(zenoh.Config.from_json5(json.dumps(cfg)))  # a link the console's router accepts
deadline = time.monotonic() + 10
while c.view().unknown == 0 and time.monotonic() < deadline:
    robot.put("arbiter/not a name/status", b"{}")  # an odd key: counted once it came through the link
    time.sleep(0.1)
threads = sorted({open(f"/proc/self/task/{t}/comm").read().strip() for t in os.listdir("/proc/self/task")})
print(json.dumps({"runtime": os.environ.get("ZENOH_RUNTIME"), "threads": threads, "odd": c.view().unknown}))
robot.close()
c.close()
"""


def run_console(env: dict[str, str]) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", CONSOLE, f"tcp/127.0.0.1:{free_port()}"],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.splitlines()[-1])


def test_the_console_takes_its_links_packets_without_an_accept_thread_and_keeps_the_users_runtime():
    env = {k: v for k, v in os.environ.items() if k != "ZENOH_RUNTIME"}
    ours = run_console(env)
    assert ours["odd"] >= 1 and ours["runtime"] == "(acc: (handover: rx))"
    assert not [t for t in ours["threads"] if t.startswith("acc-")], ours["threads"]
    assert [t for t in ours["threads"] if t.startswith("rx-")]
    theirs = run_console({**env, "ZENOH_RUNTIME": "(rx: (worker_threads: 1))"})
    assert theirs["odd"] >= 1 and theirs["runtime"] == "(rx: (worker_threads: 1))"
    assert [t for t in theirs["threads"] if t.startswith("acc-")]
