#!/usr/bin/env python
"""The console on a Raspberry Pi-class CPU: command timing at the tracker while each screen paints.

A Pi 4 core runs Python 3-4x slower than a core of a desktop; a CPU quota of 25 % of one core stands in
for one. The backend and the console each run in a cgroup of their own held to ``--quota`` (cgroup v1
``cpu`` controller, ``cpu.cfs_period_us`` 10 ms, or cgroup v2 ``cpu.max``; root needed), the console in
tmux at ``--size``. For each screen (``--screens``: control, analytics, latency, topics; the control screen
is the dashboard at 160x45 and more) a go_to_goal mission is (re)started with ``G`` and measured for
``--seconds``:

* the time between consecutive commands as the tracker received them (its records' receive times,
  paged by ``rx_seq``): p50 / p95 / max; the mission sends every 100 ms (10 Hz), and the backend stops
  the robot after 0.5 s without one;
* the console's CPU as a percentage of its quota, and the share of periods it was throttled in.

The **floor**, measured in the same run and the same cgroup: a plain roslibpy script that publishes a
stamped command every 100 ms on a monotonic schedule. And **key to wire**: ``i`` sent to the console's
terminal (tmux) until the tracker received the command, against a raw-tty roslibpy script that publishes
on each key it reads, both typed the same way (``--no-key-to-wire`` skips it). Last line: JSON.

    sudo python bench/pi.py --seconds 15            # the defaults: 25 % quota, 100x30
    python bench/pi.py --size 200x60 --pythonpath /path/to/another/checkout   # the same bench, other code
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import subprocess
import sys
import tempfile
import time
import urllib.request
import uuid
from pathlib import Path

from _common import compile_checkout, emit, pct

from arbiter_core.listening import parse_listening

TICK = os.sysconf("SC_CLK_TCK")
PERIOD_US = 10_000

FLOOR = r"""
import json, sys, time, roslibpy
ros = roslibpy.Ros(host="127.0.0.1", port=int(sys.argv[1])); ros.run()
topic = roslibpy.Topic(ros, "/stamped_cmd_vel", "std_msgs/String"); topic.advertise()
print("floor ready", flush=True)
t, end = time.monotonic(), time.monotonic() + float(sys.argv[2])
while t < end:
    t += 0.1
    time.sleep(max(0.0, t - time.monotonic()))
    stamp = time.time_ns() / 1e6
    topic.publish(roslibpy.Message({"data": json.dumps({"header": {"stamp": stamp},
                  "twist": {"linear": {"x": 0.1}, "angular": {"z": 0.0}}})}))
ros.close()
"""

RAW_TTY = r"""
import json, os, sys, termios, time, tty, roslibpy
ros = roslibpy.Ros(host="127.0.0.1", port=int(sys.argv[1])); ros.run()
topic = roslibpy.Topic(ros, "/stamped_cmd_vel", "std_msgs/String"); topic.advertise()
fd = sys.stdin.fileno(); old = termios.tcgetattr(fd); tty.setraw(fd)
print("raw ready\r", flush=True)
try:
    while True:
        key = os.read(fd, 1)
        if key == b"q":
            break
        topic.publish(roslibpy.Message({"data": json.dumps({"header": {"stamp": time.time_ns() / 1e6},
                      "twist": {"linear": {"x": 0.5}, "angular": {"z": 0.0}}})}))
finally:
    termios.tcsetattr(fd, termios.TCSADRAIN, old)
    ros.close()
"""


class Cgroup:
    """A CPU quota for the processes put in it: cgroup v1 ``cpu`` or v2 ``cpu.max``."""

    def __init__(self, name: str, quota: float) -> None:
        v1 = Path("/sys/fs/cgroup/cpu")
        self.v2 = not (v1 / "cpu.cfs_quota_us").exists()
        root = Path("/sys/fs/cgroup") if self.v2 else v1
        self.path = root / name
        self.path.mkdir(exist_ok=True)
        us = int(PERIOD_US * quota)
        if self.v2:
            (self.path / "cpu.max").write_text(f"{us} {PERIOD_US}")
        else:
            (self.path / "cpu.cfs_period_us").write_text(str(PERIOD_US))
            (self.path / "cpu.cfs_quota_us").write_text(str(us))

    def add(self, pid: int) -> None:
        (self.path / "cgroup.procs").write_text(str(pid))

    def throttling(self) -> tuple[int, int]:
        stat = dict(line.split() for line in (self.path / "cpu.stat").read_text().splitlines())
        return int(stat.get("nr_periods", 0)), int(stat.get("nr_throttled", 0))

    def remove(self) -> None:
        try:
            for pid in (self.path / "cgroup.procs").read_text().split():
                (self.path.parent / "cgroup.procs").write_text(pid)
            self.path.rmdir()
        except OSError:
            pass


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10).stdout


def cpu_seconds(pids: list[int]) -> float:
    total = 0.0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += (int(fields[11]) + int(fields[12])) / TICK
    return total


def records_since(api: str, since: int | None) -> tuple[list[dict], int | None]:
    out: list[dict] = []
    while True:
        query = "limit=1000" + (f"&since={since}" if since is not None else "")
        with urllib.request.urlopen(f"{api}/api/latency?{query}", timeout=5) as r:
            body = json.load(r)
        out.extend(body["records"])
        if body["records"]:
            since = body["records"][-1]["rx_seq"]
        if not body.get("more"):
            return out, since if since is not None else body.get("last_rx_seq")


def gaps_ms(records: list[dict]) -> list[float]:
    t = sorted(r["timestamp"] for r in records)
    return [(b - a) * 1000.0 for a, b in itertools.pairwise(t)]


def stamp_gaps_ms(records: list[dict]) -> list[float]:
    """Gaps between the senders' stamps (receive time less the one-way latency): when commands *left*."""
    t = sorted(r["timestamp"] * 1000.0 - r["latency_ms"] for r in records)
    return [b - a for a, b in itertools.pairwise(t)]


def top(values: list[float]) -> float | None:
    return round(max(values), 4) if values else None


def wait_screen(session: str, text: str, timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if text in tmux("capture-pane", "-p", "-t", session):
            return True
        time.sleep(0.05)
    return False


def start_backend(python: str, env: dict, group: Cgroup, log: Path) -> tuple[subprocess.Popen, str, int]:
    # run from a folder with no package in it: ``python -m`` puts the working directory first on
    # sys.path, ahead of PYTHONPATH, so from a checkout it would import that checkout, not --pythonpath's
    proc = subprocess.Popen(
        [python, "-m", "arbiter_backend.cli", "--bridge-port", "0", "--api-port", "0",
         "--log-file", str(log)],
        stdout=subprocess.PIPE, text=True, env=env, cwd=log.parent,
    )  # fmt: skip
    group.add(proc.pid)
    assert proc.stdout is not None
    for line in proc.stdout:
        found = parse_listening(line)
        if found is not None:
            return proc, f"http://127.0.0.1:{found.api_port}", int(found.bridge_port or 0)
    raise RuntimeError("the backend did not start")


def tree(pid: int) -> list[int]:
    out = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()
    return [pid] + [q for child in out for q in tree(int(child))]


def key_to_wire(session: str, api: str, since: int | None, presses: int, settle: float) -> list[float]:
    """``i`` typed into the terminal until the tracker received a moving command, ``presses`` times."""
    out = []
    for _ in range(presses):
        time.sleep(settle)  # the key timed out, the robot stopped: the next press is a new one
        _, since = records_since(api, since)
        t0 = time.time()
        tmux("send-keys", "-t", session, "i")
        end = time.monotonic() + 3.0
        while time.monotonic() < end:
            recs, _ = records_since(api, since)
            moving = [r for r in recs if r["linear_x"] > 0]
            if moving:
                out.append((moving[0]["timestamp"] - t0) * 1000.0)
                break
            time.sleep(0.005)
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=15.0, help="measured per screen")
    p.add_argument("--quota", type=float, default=0.25, help="CPU quota of each cgroup, in cores")
    p.add_argument("--size", default="100x30", help="terminal size, COLSxROWS")
    p.add_argument("--presses", type=int, default=40, help="key presses for key-to-wire")
    p.add_argument("--pythonpath", help="measure the code of another checkout (its root)")
    p.add_argument(
        "--screens",
        default="control,analytics,latency,topics",
        help="screens measured, in order (control is the dashboard at 160x45 and more)",
    )
    p.add_argument("--no-key-to-wire", action="store_true", help="skip the key-to-wire comparison")
    p.add_argument("--records", type=Path, help="the tracker's records of each screen, as JSON lines")
    p.add_argument(
        "--cold-sweep",
        action="store_true",
        help="the console with an empty cache directory: the analytics sweep has never run (its child "
        "starts when the analytics screen opens, in the console's cgroup)",
    )
    a = p.parse_args()
    if os.geteuid() != 0:
        print("pi: needs root (cgroups)", file=sys.stderr)
        return 1
    compile_checkout(a.pythonpath)  # compiled, as an installed copy is
    env = dict(os.environ)
    if a.pythonpath:
        env["PYTHONPATH"] = a.pythonpath
    python = sys.executable
    cols, rows = a.size.split("x")
    tag = uuid.uuid4().hex[:6]
    backend_group = Cgroup(f"arbiter-pi-backend-{tag}", a.quota)
    console_group = Cgroup(f"arbiter-pi-console-{tag}", a.quota)
    tmp = Path(tempfile.mkdtemp())
    if a.cold_sweep:
        env["XDG_CACHE_HOME"] = str(tmp / "cache")
    backend, api, bridge = start_backend(python, env, backend_group, tmp / "backend.log")
    result: dict = {"bench": "pi", "quota_cores": a.quota, "size": a.size, "seconds": a.seconds,
                    "cold_sweep": a.cold_sweep}  # fmt: skip
    try:
        # the floor: a plain roslibpy script at 10 Hz, in the console's cgroup
        _, since = records_since(api, None)
        floor = subprocess.Popen([python, "-c", FLOOR, str(bridge), str(a.seconds + 2)], env=env, cwd=tmp,
                                 stdout=subprocess.PIPE, text=True)  # fmt: skip
        console_group.add(floor.pid)
        floor.wait(timeout=a.seconds + 60)
        recs, since = records_since(api, since)
        g = gaps_ms(recs)[5:]
        result["floor"] = {"gap_p50_ms": pct(g, 0.5), "gap_p95_ms": pct(g, 0.95), "gap_max_ms": top(g)}

        # the console, screen by screen, a mission driving
        session = f"arbiter-pi-{tag}"
        cache = f"XDG_CACHE_HOME={tmp / 'cache'}" if a.cold_sweep else ""
        cmd = (
            f"env PYTHONPATH={env.get('PYTHONPATH', '')} {cache} {python} -m arbiter_tui.cli --connect "
            f"--rosbridge ws://127.0.0.1:{bridge} --tracker {api} --export-dir {tmp} "
            f"--log-file {tmp / 'tui.log'}"
        )
        tmux("new-session", "-d", "-s", session, "-x", cols, "-y", rows, "-c", str(tmp), cmd)
        pane = int(tmux("display-message", "-p", "-t", session, "#{pane_pid}").strip())
        for pid in tree(pane):
            console_group.add(pid)
        if not wait_screen(session, "CONNECTED", 60):
            raise RuntimeError("the console did not connect: " + tmux("capture-pane", "-p", "-t", session))
        tmux("send-keys", "-t", session, "a")  # go_to_goal
        time.sleep(0.5)
        screens = {}
        keys = {"control": "1", "analytics": "2", "latency": "3", "topics": "4"}
        for name in a.screens.split(","):
            key = keys[name]
            tmux("send-keys", "-t", session, "1")
            time.sleep(0.3)
            tmux("send-keys", "-t", session, "G")  # the square from its first waypoint, from here
            time.sleep(0.3)
            tmux("send-keys", "-t", session, key)
            # the screen is up and the mission under way (a cold sweep: measured from the screen's
            # opening, where its child starts)
            time.sleep(0.2 if a.cold_sweep else 2.0)
            _, since = records_since(api, since)
            pids, bpids = tree(pane), tree(backend.pid)
            c0, (n0, th0), t0 = cpu_seconds(pids), console_group.throttling(), time.monotonic()
            b0, (bn0, bth0) = cpu_seconds(bpids), backend_group.throttling()
            time.sleep(a.seconds / 2)
            pane_text = tmux("capture-pane", "-p", "-t", session)  # half-way: the mission drives
            time.sleep(a.seconds / 2)
            dt = time.monotonic() - t0
            cpu = cpu_seconds(pids) - c0
            n1, th1 = console_group.throttling()
            bcpu = cpu_seconds(bpids) - b0
            bn1, bth1 = backend_group.throttling()
            recs, since = records_since(api, since)
            if a.records:
                with a.records.open("a") as f:
                    f.writelines(json.dumps({"size": a.size, "screen": name, **r}) + "\n" for r in recs)
            g = gaps_ms(recs)
            # on a terminal of 160x45 and more the control screen is the dashboard
            big = int(cols) >= 160 and int(rows) >= 45
            screens["dashboard" if name == "control" and big else name] = {
                "commands": len(recs),
                "gap_p50_ms": pct(g, 0.5), "gap_p95_ms": pct(g, 0.95), "gap_max_ms": top(g),
                # a steadier figure than one run's p95 (the 6th largest of 120 gaps)
                "gaps_over_110_ms_percent": round(100 * sum(x > 110 for x in g) / max(1, len(g)), 1),
                # where a long gap came from: the command left late (the stamps' gaps) or was slow on
                # its way (the one-way latency: the link's thread, the socket, the backend's loop)
                "stamp_gap_p95_ms": pct(sg := stamp_gaps_ms(recs), 0.95), "stamp_gap_max_ms": top(sg),
                "one_way_p50_ms": pct(ow := [r["latency_ms"] for r in recs], 0.5),
                "one_way_p95_ms": pct(ow, 0.95), "one_way_max_ms": top(ow),
                "cpu_percent_of_quota": round(100 * cpu / dt / a.quota, 1),
                "throttled_percent_of_periods": round(100 * (th1 - th0) / max(1, n1 - n0), 1),
                # the backend receives the commands: its own quota can stretch the gaps too
                "backend_cpu_percent_of_quota": round(100 * bcpu / dt / a.quota, 1),
                "backend_throttled_percent_of_periods": round(100 * (bth1 - bth0) / max(1, bn1 - bn0), 1),
                # where the long gaps were: seconds into the measurement, and the gap
                "gaps_over_150_ms": [(round(i * 0.1, 1), round(x)) for i, x in enumerate(g) if x > 150],
                # the analytics sweep held while the robot drives (a console with no core to spare)
                "sweep_paused_on_screen": "paused while the robot drives" in " ".join(pane_text.split()),
            }  # fmt: skip
            tmux("send-keys", "-t", session, "space")
        result["console"] = screens

        if not a.no_key_to_wire:
            # key to wire: the console (control screen) against a raw-tty roslibpy script, typed alike
            tmux("send-keys", "-t", session, "1")
            time.sleep(1.0)
            k = key_to_wire(session, api, since, a.presses, 1.0)
            result["key_to_wire_console"] = {"n": len(k), "p50_ms": pct(k, 0.5), "p95_ms": pct(k, 0.95)}
            tmux("send-keys", "-t", session, "C-q")
            time.sleep(1.0)
            raw_session = f"arbiter-pi-raw-{tag}"
            script = tmp / "raw.py"
            script.write_text(RAW_TTY)
            tmux("new-session", "-d", "-s", raw_session, "-x", cols, "-y", rows, "-c", str(tmp),
                 f"env PYTHONPATH={env.get('PYTHONPATH', '')} {python} {script} {bridge}")  # fmt: skip
            raw_pane = int(tmux("display-message", "-p", "-t", raw_session, "#{pane_pid}").strip())
            for pid in tree(raw_pane):
                console_group.add(pid)
            wait_screen(raw_session, "raw ready", 30)
            _, since = records_since(api, None)
            k = key_to_wire(raw_session, api, since, a.presses, 0.3)
            result["key_to_wire_raw_tty"] = {"n": len(k), "p50_ms": pct(k, 0.5), "p95_ms": pct(k, 0.95)}
            tmux("send-keys", "-t", raw_session, "q")
            con, raw = result["key_to_wire_console"]["p95_ms"], result["key_to_wire_raw_tty"]["p95_ms"]
            result["key_to_wire_p95_ratio"] = round(con / raw, 2) if con and raw else None
    finally:
        for s in (f"arbiter-pi-{tag}", f"arbiter-pi-raw-{tag}"):
            tmux("kill-session", "-t", s)
        backend.terminate()
        backend.wait(timeout=10)
        backend_group.remove()
        console_group.remove()
    emit(result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
