"""The fleet at scale (issue 49): the console's CPU against the number of robots, kill -9 -> "lost" and
restart -> "alive" on the screen, bytes/s per robot, and a robot behind a bad link (netem).

The console is ``arbiter-tui fleet --listen`` (it is the site's router) in a real terminal (tmux, 200x60);
N simulated robots are one process publishing as N robots on the schema of ``arbiter_core.fleet`` at its
rates (each its own liveliness token and payloads, phases spread over the period), beside 3 real
``arbiter-backend --zenoh`` processes named ``real-1..3`` (they sort before ``sim-*`` among the healthy
rows, so their rows are on the screen). An observer in this process (the console's own client code, a
Zenoh client of the console) counts the bytes each robot sends and sees the tokens go.

- CPU: the console process's utime+stime over ``--seconds``, after the rows are all there and a warm-up,
  for each N of ``--robots`` (a new console each time: lost rows are never dropped);
- freeze -> lost: SIGSTOP of a real backend (its socket stays open: only its lease, 1500 ms, tells)
  until its row reads "lost"; SIGCONT until it is back;
- kill -> lost: ``kill -9`` of a real backend until its row on the screen (tmux capture, every 20 ms)
  reads "lost since", and until the observer's row does (without the screen's 0.5 s refresh);
  restart -> alive: a new backend with the same name until its row reads "alive" again;
- bytes/s: payload bytes each robot sent over the CPU window, from the observer's counts;
- ``--quota PCT``: the console under a CPU quota (cgroup v1, ``/sys/fs/cgroup/cpu/fleetbench``: PCT % of a
  core, as a Raspberry Pi's share might be; root): its CPU as a share of the quota, the periods it was
  throttled in, and how soon a killed robot's row is the first on the screen;
- ``--stops K``: at the largest N, the stop from the fleet (``arbiter/<name>/stop``) asked K times of a
  real backend through the console's router by the observer: its latency, p50/p95/max;
- ``--cpu-only``: the CPU (whole and per thread) and the rows alone, without the kill/restart, stops and
  quota; ``--console-root DIR``: the console's code from another checkout (to compare two versions in
  alternating runs: the machine's load moves the figures by a point or two between runs);
- ``--netem``: a 4th backend in a network namespace (root) behind a link that delays and drops packets
  both ways (``--delay-ms``, ``--loss``; ``tunlink.py``: this kernel has no ``sch_netem``, so the link is
  impaired in user space, packet by packet), for ``--netem-seconds``: the time its row was not "alive",
  its figures, and its bytes on the link (IP packets: Zenoh, TCP and IP headers included).

    nice -n 10 python bench/fleet.py --robots 10,50,200 --seconds 20 --netem
    python bench/fleet.py --robots 200,500 --seconds 20 --stops 100 --quota 25
    nice -n 10 python bench/fleet.py --robots 200,500 --cpu-only --console-root ../base
"""

from __future__ import annotations

import argparse
import contextlib
import heapq
import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

from _common import emit, free_port, pct

ROOT = Path(__file__).resolve().parents[1]
SESSION = f"fleetbench-{os.getpid()}"  # its own: two benches at once must not kill each other's
NS, HOST_IP, BOT_IP = "fleetbot", "10.201.0.1", "10.201.0.2"
CLK_TCK = os.sysconf("SC_CLK_TCK")
CGROUP = Path("/sys/fs/cgroup/cpu/fleetbench")


def env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"}


# -- N robots in one process --------------------------------------------------------------------------
def simulate(n: int, endpoint: str, prefix: str) -> None:
    """Publish as ``n`` robots until killed (the child process of the bench)."""
    import zenoh

    from arbiter_core import fleet

    cfg = {
        "mode": "client",
        "connect": {"endpoints": [endpoint], "timeout_ms": -1},
        "scouting": {"multicast": {"enabled": False}},
    }
    session = zenoh.open(zenoh.Config.from_json5(json.dumps(cfg)))
    names = [f"{prefix}-{i:03d}" for i in range(n)]
    keep = [session.liveliness().declare_token(fleet.key(name, fleet.ALIVE)) for name in names]
    pubs = {(name, k): session.declare_publisher(fleet.key(name, k)) for name in names for k in fleet.KINDS}
    rng = random.Random(1)
    started = time.time()
    topics = [
        ("/odom", 50.0),
        ("/scan", 10.0),
        ("/imu", 100.0),
        ("/tf", 50.0),
        ("/camera/image_raw", 15.0),
        ("/cmd_vel", 10.0),
        ("/battery", 1.0),
        ("/diagnostics", 1.0),
    ]

    def payload(name: str, kind: str) -> bytes:
        now = time.time()
        if kind == fleet.STATUS:
            p = fleet.Status(
                name,
                now,
                started,
                "robot",
                "embedded, sim, autonomy",
                "none",
                "pure_pursuit on square",
                "pure_pursuit",
                "square",
                "running",
                2,
                4,
                (rng.uniform(-5, 5), rng.uniform(-5, 5), 0.3),
                (0.5, 0.1),
                f"ws://{name}.lab:9090",
                f"http://{name}.lab:8085",
                None,
                3,
                1500,
            )
        elif kind == fleet.LATENCY:
            p = fleet.Latency(name, now, 400, 9000, 1.2, rng.uniform(2, 9), 12.0, 0, 0, "chrony", True, 0.4)
        else:
            items = tuple(fleet.TopicHealth(t, "ok", hz, 20.0) for t, hz in topics)
            p = fleet.Topics(name, now, 5.0, len(items), items)
        return fleet.encode(p)

    due = [
        (time.monotonic() + i / n * fleet.PERIOD_S[k], name, k)
        for i, name in enumerate(names)
        for k in (fleet.STATUS, fleet.LATENCY, fleet.TOPICS)
    ]
    heapq.heapify(due)
    print("publishing", flush=True)
    while True:
        at, name, kind = heapq.heappop(due)
        d = at - time.monotonic()
        if d > 0:
            time.sleep(d)
        pubs[(name, kind)].put(payload(name, kind))
        heapq.heappush(due, (at + fleet.PERIOD_S[kind], name, kind))
    del keep


# -- the pieces the bench starts ----------------------------------------------------------------------
def tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, timeout=10).stdout


def start_console(listen: str, size: tuple[int, int], root: Path | None = None) -> int:
    """The fleet screen in tmux; its process id (``exec``: the pane's process is the console). Its code:
    ``root`` (another checkout, to compare two versions in alternating runs), else this one."""
    tmux("kill-session", "-t", SESSION)
    root = root or ROOT
    cmd = f"exec env PYTHONPATH={root} {sys.executable} -m arbiter_tui.cli fleet --listen {listen}"
    # started in ``root``: ``python -m`` puts its working directory before PYTHONPATH
    tmux("new-session", "-d", "-s", SESSION, "-c", str(root), "-x", str(size[0]), "-y", str(size[1]), cmd)
    return int(tmux("display-message", "-p", "-t", SESSION, "#{pane_pid}").strip())


def screen() -> str:
    return tmux("capture-pane", "-p", "-t", SESSION)


def first_row() -> str | None:
    """The name on the list's first row (below its column header; a "worse above" line skipped)."""
    lines = screen().splitlines()
    for i, line in enumerate(lines):
        if line.split()[:1] == ["robot"]:
            for below in lines[i + 1 :]:
                cells = below.split()
                if cells and not cells[0].startswith("▲"):
                    return cells[0]
    return None


def quota(pid: int, percent: float) -> None:
    """The console (and its threads) under ``percent`` % of one core: a cgroup v1 CFS quota."""
    CGROUP.mkdir(exist_ok=True)
    period = int((CGROUP / "cpu.cfs_period_us").read_text())
    (CGROUP / "cpu.cfs_quota_us").write_text(str(int(period * percent / 100)))
    (CGROUP / "cgroup.procs").write_text(str(pid))


def throttling() -> tuple[int, int]:
    """(periods, throttled periods) of the quota's cgroup so far."""
    stat = dict(line.split() for line in (CGROUP / "cpu.stat").read_text().splitlines())
    return int(stat["nr_periods"]), int(stat["nr_throttled"])


def stop_latency(obs, name: str, count: int) -> dict:
    """The fleet's stop asked ``count`` times of ``name`` through the router: seconds until its answer."""
    took, answers = [], set()
    for _ in range(count):
        t0 = time.perf_counter()
        answer = obs.stop(name)
        took.append(time.perf_counter() - t0)
        answers.add(answer if isinstance(answer, str) else answer.words())
        time.sleep(0.05)
    return {
        "count": count,
        "ms_p50_p95_max": [round(1e3 * v, 1) for v in (pct(took, 0.5), pct(took, 0.95), max(took))],
        "answers": sorted(answers),
    }


def screen_state(name: str) -> str | None:
    for line in screen().splitlines():
        cells = line.split()
        if cells and cells[0] == name:
            return cells[1]
    return None


def start_backend(
    endpoint: str, name: str, netns: str | None = None, lease_ms: int | None = None
) -> subprocess.Popen:
    cmd = [
        sys.executable,
        "-m",
        "arbiter_backend.cli",
        "--bridge-port",
        "0",
        "--api-port",
        "0",
        "--zenoh",
        endpoint,
        "--robot-name",
        name,
    ]
    if lease_ms is not None:
        cmd += ["--zenoh-lease", str(lease_ms)]
    if netns is not None:
        cmd = ["ip", "netns", "exec", netns, "env", f"PYTHONPATH={ROOT}", *cmd]
    p = subprocess.Popen(cmd, env=env(), stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    assert p.stdout is not None
    if "listening" not in p.stdout.readline():
        raise RuntimeError(f"backend {name} did not start")
    return p


def start_sim(n: int, endpoint: str) -> subprocess.Popen:
    p = subprocess.Popen(
        [sys.executable, __file__, "--simulate", str(n), "--endpoint", endpoint],
        env=env(),
        stdout=subprocess.PIPE,
        text=True,
    )
    assert p.stdout is not None
    p.stdout.readline()
    return p


def cpu_s(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK


def thread_cpu_s(pid: int) -> dict[str, float]:
    """Each of the process's threads' utime+stime so far (s), summed by thread name (Zenoh's runtime
    threads share names: ``rx-0``, ``net-0``, ...)."""
    out: dict[str, float] = {}
    for task in Path(f"/proc/{pid}/task").iterdir():
        with contextlib.suppress(OSError):
            head, rest = task.joinpath("stat").read_text().rsplit(")", 1)
            name = head.split("(", 1)[1]
            fields = rest.split()
            out[name] = out.get(name, 0.0) + (int(fields[11]) + int(fields[12])) / CLK_TCK
    return out


def wait(pred, timeout: float, interval: float = 0.05) -> float | None:
    """Seconds until ``pred()`` holds, or None after ``timeout``."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if pred():
            return time.monotonic() - t0
        time.sleep(interval)
    return None


def observer(endpoint: str):
    from arbiter_tui.fleet.client import ConsoleSettings, FleetClient

    c = FleetClient(ConsoleSettings(connect=(endpoint,)))
    c.open(connect_timeout_ms=10_000)
    return c


def obs_state(c, name: str) -> str | None:
    r = c.row(name)
    return None if r is None else r.state


# -- the measurements -----------------------------------------------------------------------------------
def scale(n: int, seconds: float, size: tuple[int, int]) -> dict:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    pid = start_console(endpoint, size, ARGS.console_root)
    procs: list[subprocess.Popen] = []
    obs = None
    try:
        time.sleep(1.0)
        obs = observer(endpoint)
        procs += [start_backend(endpoint, f"real-{i}") for i in (1, 2, 3)]
        procs.append(start_sim(n, endpoint))
        shown = wait(lambda: obs.view().total >= n + 3 and all(r.driver for r in obs.view().rows), 60)
        time.sleep(5.0)  # warm-up: every robot's topics period has gone by
        # bytes/s per robot, counted by the observer (a second console, subscribed through the console)...
        before, t0 = obs.model.received_bytes(), time.monotonic()
        time.sleep(min(seconds, 10.0))
        after, window = obs.model.received_bytes(), time.monotonic() - t0
        rates = {k: (after[k] - before.get(k, 0)) / window for k in after}
        # ...then the console's CPU with the observer gone: the console routes to itself alone
        obs.close()
        time.sleep(1.0)
        if ARGS.quota:
            quota(pid, ARGS.quota)
            time.sleep(2.0)  # the quota's first periods
            p0, th0 = throttling()
        c0, threads0, t0 = cpu_s(pid), thread_cpu_s(pid), time.monotonic()
        time.sleep(seconds)
        window = time.monotonic() - t0
        cpu = 100.0 * (cpu_s(pid) - c0) / window
        threads1 = thread_cpu_s(pid)
        by_thread = {k: round(100.0 * (v - threads0.get(k, 0.0)) / window, 1) for k, v in threads1.items()}
        listed = screen().split("────")[0].splitlines()  # the list, above the detail pane's rule
        rows_on_screen = sum(
            1 for line in listed if line.split()[:1] and line.split()[0].startswith(("sim-", "real-"))
        )
        obs = observer(endpoint)
        sim_rates = [v for k, v in rates.items() if k.startswith("sim-")]
        real_rates = [v for k, v in rates.items() if k.startswith("real-")]
        result = {
            "robots": n + 3,
            "console_cpu_percent": round(cpu, 1),
            "console_cpu_percent_by_thread": {k: v for k, v in sorted(by_thread.items()) if v > 0},
            **({} if not ARGS.quota else quota_figures(cpu, p0, th0)),
            "rows_on_screen": rows_on_screen,
            "all_rows_after_s": None if shown is None else round(shown, 2),
            "sim_bytes_per_s_p50": round(pct(sim_rates, 0.5) or 0, 1),
            "real_bytes_per_s": [round(v, 1) for v in real_rates],
        }
        wait(lambda: obs.view().total >= n + 3, 10)
        if ARGS.cpu_only:
            return result
        if n == max(ARGS.robots) and ARGS.stops:
            result["stop"] = stop_latency(obs, "real-1", ARGS.stops)
        if n == max(ARGS.robots) or ARGS.quota:
            result["kill_restart"] = kill_restart(endpoint, procs, obs)
        return result
    finally:
        for p in procs:
            with contextlib.suppress(ProcessLookupError):
                p.kill()
            p.wait()
        if obs is not None:
            obs.close()
        tmux("kill-session", "-t", SESSION)


def quota_figures(cpu: float, p0: int, th0: int) -> dict:
    periods, throttled = throttling()
    return {
        "quota_percent_of_a_core": ARGS.quota,
        "console_cpu_percent_of_quota": round(100.0 * cpu / ARGS.quota, 1),
        "throttled_periods_percent": round(100.0 * (throttled - th0) / max(1, periods - p0), 1),
    }


def first_times(t0: float, probes: dict, timeout: float) -> dict:
    """Seconds from ``t0`` until each probe first held (polled together, every 20 ms); None: never."""
    out = dict.fromkeys(probes)
    while time.monotonic() - t0 < timeout and any(v is None for v in out.values()):
        for key, probe in probes.items():
            if out[key] is None and probe():
                out[key] = round(time.monotonic() - t0, 3)
        time.sleep(0.02)
    return out


def kill_restart(endpoint: str, procs: list[subprocess.Popen], obs) -> dict:
    """Each real backend killed (-9) in turn, then started again under its name: the seconds until its row
    reads "lost" (then "alive"), on the screen and in the observer (which has no screen refresh)."""
    out: dict[str, list] = {
        "kill_to_lost_screen_s": [],
        "kill_to_lost_observer_s": [],
        "restart_to_alive_screen_s": [],
        "restart_to_alive_observer_s": [],
        "restart_to_listening_s": [],
        "kill_to_first_row_screen_s": [],  # the killed robot's row the first on the screen
    }
    # frozen first (SIGSTOP: its socket stays open, only the lease tells), then thawed
    out["freeze_to_lost_screen_s"], out["freeze_to_lost_observer_s"], out["thaw_to_alive_observer_s"] = (
        [],
        [],
        [],
    )
    for i in (1, 2, 3):
        name = f"real-{i}"
        t0 = time.monotonic()
        os.kill(procs[i - 1].pid, signal.SIGSTOP)
        lost = first_times(
            t0,
            {
                "screen": lambda n=name: screen_state(n) == "lost",
                "observer": lambda n=name: obs_state(obs, n) == "lost",
            },
            10,
        )
        t1 = time.monotonic()
        os.kill(procs[i - 1].pid, signal.SIGCONT)
        back = first_times(t1, {"observer": lambda n=name: obs_state(obs, n) == "alive"}, 20)
        out["freeze_to_lost_screen_s"].append(lost["screen"])
        out["freeze_to_lost_observer_s"].append(lost["observer"])
        out["thaw_to_alive_observer_s"].append(back["observer"])
        time.sleep(1.0)
    for i in (1, 2, 3):
        name = f"real-{i}"
        t0 = time.monotonic()
        procs[i - 1].kill()
        lost = first_times(
            t0,
            {
                "screen": lambda n=name: screen_state(n) == "lost",
                "observer": lambda n=name: obs_state(obs, n) == "lost",
                "first": lambda n=name: first_row() == n and screen_state(n) == "lost",
            },
            10,
        )
        out["kill_to_first_row_screen_s"].append(lost["first"])
        procs[i - 1].wait()
        t1 = time.monotonic()
        procs[i - 1] = start_backend(endpoint, name)
        listening = round(time.monotonic() - t1, 3)
        alive = first_times(
            t1,
            {
                "screen": lambda n=name: screen_state(n) == "alive",
                "observer": lambda n=name: obs_state(obs, n) == "alive",
            },
            20,
        )
        out["kill_to_lost_screen_s"].append(lost["screen"])
        out["kill_to_lost_observer_s"].append(lost["observer"])
        out["restart_to_alive_screen_s"].append(alive["screen"])
        out["restart_to_alive_observer_s"].append(alive["observer"])
        out["restart_to_listening_s"].append(listening)
        time.sleep(1.0)
    return out


def netem(delay_ms: float, loss: float, seconds: float, lease_ms: int) -> dict:
    """A backend in a network namespace behind a link that delays and drops packets both ways
    (``tunlink.TunLink``: this kernel has no ``sch_netem``, so the link is impaired in user space)."""
    from tunlink import TunLink

    with TunLink(NS, delay_ms / 1000, loss, HOST_IP, BOT_IP) as link:
        port = free_port()
        local, remote = f"tcp/127.0.0.1:{port}", f"tcp/{HOST_IP}:{port}"
        pid = start_console(f"{local},{remote}", (200, 60))
        time.sleep(1.0)
        obs = observer(local)
        t_start = time.monotonic()
        bot = start_backend(remote, "netem-1", netns=NS, lease_ms=lease_ms)
        try:
            up = wait(
                lambda: (
                    (r := obs.row("netem-1")) is not None
                    and r.driver is not None
                    and r.latency_count is not None
                ),
                60,
            )
            up_s = None if up is None else round(time.monotonic() - t_start, 2)
            b0, c0, t0, drops0, pk0 = link.bytes_in, cpu_s(pid), time.monotonic(), link.dropped, link.packets
            not_alive, times_not_alive, last, ages = 0.0, 0, "alive", []
            while time.monotonic() - t0 < seconds:
                r = obs.row("netem-1")
                s = None if r is None else r.state
                if s != "alive":
                    not_alive += 0.1
                times_not_alive += s != last and s != "alive"
                last = s
                if r is not None and r.age_s is not None:
                    ages.append(r.age_s)
                time.sleep(0.1)
            window = time.monotonic() - t0
            row = obs.row("netem-1")
            return {
                "link": "user-space TUN (no sch_netem in this kernel)",
                "delay_ms_each_way": delay_ms,
                "loss_each_way": loss,
                "lease_ms": lease_ms,
                "seconds": round(window, 1),
                "start_to_figures_s": up_s,
                "packets_dropped": f"{link.dropped - drops0} of {link.packets - pk0}",
                "not_alive_s": round(not_alive, 1),
                "times_not_alive": times_not_alive,
                "state_at_end": None if row is None else row.state,
                "payload_age_s_p50_p95_max": [
                    pct(ages, 0.5),
                    pct(ages, 0.95),
                    round(max(ages), 2) if ages else None,
                ],
                "figures_at_end": None
                if row is None
                else {
                    "worst_topic": row.worst_topic,
                    "driver": row.driver,
                    "latency_count": row.latency_count,
                },
                "wire_bytes_per_s_robot_to_console": round((link.bytes_in - b0) / window, 1),
                "console_cpu_percent": round(100.0 * (cpu_s(pid) - c0) / window, 1),
            }
        finally:
            bot.kill()
            bot.wait()
            obs.close()
            tmux("kill-session", "-t", SESSION)


def main() -> None:
    global ARGS
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--robots",
        type=lambda t: [int(x) for x in t.split(",") if x.strip()],
        default=[10, 50, 200],
        help="simulated robots per run, e.g. 10,50,200 ('' for the --netem case alone)",
    )
    p.add_argument("--seconds", type=float, default=20.0, help="each CPU window (default 20)")
    p.add_argument("--size", default="200x60")
    p.add_argument("--quota", type=float, help="the console under this %% of a core (cgroup v1; root)")
    p.add_argument("--stops", type=int, default=0, help="stops asked of a robot at the largest N")
    p.add_argument("--cpu-only", action="store_true", help="the CPU and rows alone (no kill, stop, restart)")
    p.add_argument(
        "--console-root",
        type=Path,
        help="the console's code from this checkout (default: this one), to compare two in alternating runs",
    )
    p.add_argument("--netem", action="store_true", help="also the robot behind netem (root)")
    p.add_argument("--delay-ms", type=float, default=200.0)
    p.add_argument("--loss", type=float, default=0.05)
    p.add_argument("--netem-seconds", type=float, default=60.0)
    p.add_argument("--netem-lease-ms", type=int, default=1500)
    p.add_argument("--simulate", type=int, help=argparse.SUPPRESS)
    p.add_argument("--endpoint", help=argparse.SUPPRESS)
    ARGS = p.parse_args()
    if ARGS.simulate is not None:
        simulate(ARGS.simulate, ARGS.endpoint, "sim")
        return
    size = tuple(int(v) for v in ARGS.size.split("x"))
    rows = []
    for n in ARGS.robots:
        r = scale(n, ARGS.seconds, size)  # type: ignore[arg-type]
        print(json.dumps(r), flush=True)
        rows.append(r)
    out = {"bench": "fleet", "size": ARGS.size, "seconds": ARGS.seconds, "quota": ARGS.quota, "scale": rows}
    if ARGS.quota:
        with contextlib.suppress(OSError):
            CGROUP.rmdir()
    if ARGS.netem:
        out["netem"] = netem(ARGS.delay_ms, ARGS.loss, ARGS.netem_seconds, ARGS.netem_lease_ms)
        print(json.dumps(out["netem"]), flush=True)
    emit(out)


ARGS: argparse.Namespace


if __name__ == "__main__":
    with contextlib.suppress(KeyboardInterrupt):
        signal.signal(signal.SIGTERM, lambda *a: sys.exit(1))
        main()
