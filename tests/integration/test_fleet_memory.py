"""The fleet console's memory after a flood (issue 56): a robot on the console's own host that sends big
payloads does not leave its shared-memory pool mapped in the console (Zenoh would carry them through a
16 MB pool of the robot's that stayed resident in the console), and the heap's free pages go back to the
system (``arbiter_tui.fleet.memory``). The figures: ``bench/fleet_flood.py``."""

import ctypes
import subprocess
import sys
import time
from pathlib import Path

from arbiter_tui.fleet import memory
from arbiter_tui.fleet.client import ConsoleSettings, FleetClient

from ..support.backend import free_port
from ..support.waits import wait_for

ROBOT = """
import json, sys, zenoh
cfg = {"mode": "client", "connect": {"endpoints": [sys.argv[1]]}}
cfg["scouting"] = {"multicast": {"enabled": False}}
s = zenoh.open(zenoh.Config.from_json5(json.dumps(cfg)))
big = b"{" + b" " * (256 * 1024)
for line in sys.stdin:  # a big status each time it is asked
    s.put("arbiter/big-1/status", big)
"""


def zenoh_segments() -> set[str]:
    """The Zenoh shared-memory segments this process maps."""
    return {
        line.split()[-1]
        for line in Path("/proc/self/maps").read_text().splitlines()
        if "/dev/shm/" in line and line.endswith(".zenoh")
    }


def test_big_payloads_from_a_robot_on_this_host_leave_no_shared_memory_mapped_in_the_console():
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    before = zenoh_segments()
    console = FleetClient(ConsoleSettings(listen=(endpoint,)))
    console.open()
    robot = subprocess.Popen(
        [sys.executable, "-c", ROBOT, endpoint], stdin=subprocess.PIPE, text=True, stderr=subprocess.PIPE
    )
    assert robot.stdin is not None
    try:

        def marked() -> bool:  # asked again until its link is up and a payload has come
            row = console.row("big-1")
            if row is not None and row.bad is not None:
                return True
            robot.stdin.write("\n")
            robot.stdin.flush()
            return False

        assert wait_for(marked, timeout=15, interval=0.3)
        row = console.row("big-1")
        assert row is not None and "status: 262.1 kB, over the 1.5 kB a status may be" in (row.bad or "")
        assert zenoh_segments() - before == set()
    finally:
        robot.kill()
        robot.wait()
        console.close()


def test_the_heaps_free_pages_go_back_to_the_system():
    libc = ctypes.CDLL(None)
    libc.malloc.restype, libc.malloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t]
    libc.free.argtypes = [ctypes.c_void_p]

    def rss_mb() -> float:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
        raise AssertionError("no VmRSS")

    # 80 MB in 4 kB blocks, written; 15 blocks of 16 freed: holes the heap's top cannot give back
    blocks = [libc.malloc(4096) for _ in range(20_000)]
    for b in blocks:
        ctypes.memset(b, 1, 4096)
    kept = blocks[::16]
    for i, b in enumerate(blocks):
        if i % 16:
            libc.free(b)
    held = rss_mb()
    t0 = time.perf_counter()
    assert memory.trim()
    took = time.perf_counter() - t0
    try:
        assert held - rss_mb() > 40, (held, rss_mb())
        assert took < 0.5
    finally:
        for b in kept:
            libc.free(b)
