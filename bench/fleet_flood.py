"""The fleet console's memory through floods (issue 56): its resident memory (VmRSS) at N robots before,
during and after a flood, round after round. Does it come back?

The console is ``arbiter-tui fleet --listen`` in tmux (200x60) beside N simulated robots
(``bench/fleet.py``'s, on the schema's rates). Each round, for ``--flood-seconds``: ``flood-1`` sends
``--rate`` valid status payloads a second (each a new one, as a robot gone mad would), and ``big-1``
sends ``--big-rate`` status payloads of ``--big-bytes`` each (over the size a status may be: marked, never
copied); then both send one status a second again, for ``--after`` seconds. The console's RSS is read
every ``--every`` seconds; the screen's ``flood-1`` row is read once during each flood (it should say
"flooding").

    nice -n 10 python bench/fleet_flood.py --robots 200 --rounds 3
    python bench/fleet_flood.py --console-root ../base   # another checkout's console, the same load
"""

from __future__ import annotations

import argparse
import contextlib
import json
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import fleet as fb  # bench/fleet.py: the console in tmux, the simulated robots
from _common import emit, free_port, rss_kb

FLOODERS = ("flood-1", "big-1")


# -- the two robots that flood, in a child process ---------------------------------------------------
def publish(endpoint: str, rate: float, big_rate: float, big_bytes: int) -> None:
    """``flood-1`` and ``big-1``: one status a second each, and a flood each time a line arrives on
    stdin (``flood SECONDS``); ``flooded`` on stdout when it has ended. Until stdin closes."""
    import threading

    import zenoh

    from arbiter_core import fleet

    cfg = {
        "mode": "client",
        "connect": {"endpoints": [endpoint], "timeout_ms": -1},
        "scouting": {"multicast": {"enabled": False}},
    }
    session = zenoh.open(zenoh.Config.from_json5(json.dumps(cfg)))
    keep = [session.liveliness().declare_token(fleet.key(name, fleet.ALIVE)) for name in FLOODERS]
    pubs = {name: session.declare_publisher(fleet.key(name, fleet.STATUS)) for name in FLOODERS}
    started, rng = time.time(), random.Random(2)

    def status(name: str) -> bytes:
        pose = (rng.uniform(-5, 5), rng.uniform(-5, 5), 0.0)
        return fleet.encode(fleet.Status(name, time.time(), started, "nobody", "embedded, sim", pose=pose))

    big = b'{"v":1,"kind":"status","robot":"big-1","pad":"' + b"x" * big_bytes + b'"}'
    flood_until = [0.0]

    def lines() -> None:
        for line in sys.stdin:
            words = line.split()
            if words[:1] == ["flood"]:
                flood_until[0] = time.monotonic() + float(words[1])
        flood_until[0] = -1.0

    threading.Thread(target=lines, daemon=True).start()
    print("publishing", flush=True)
    next_normal = time.monotonic()
    while flood_until[0] >= 0:  # -1: stdin closed
        now = time.monotonic()
        if now < flood_until[0]:  # the flood: paced by a clock, in steps of a millisecond
            t0, sent_big = now, 0.0
            n = 0
            while time.monotonic() < flood_until[0]:
                if time.monotonic() >= next_normal:  # each its status a second, flood or not
                    for name in FLOODERS:
                        pubs[name].put(status(name))
                    next_normal += 1.0
                elapsed = time.monotonic() - t0
                while n < elapsed * rate:
                    pubs["flood-1"].put(status("flood-1"))
                    n += 1
                while sent_big < elapsed * big_rate:
                    pubs["big-1"].put(big)
                    sent_big += 1
                time.sleep(0.001)
            print(f"flooded {n} {int(sent_big)}", flush=True)
        if now >= next_normal:
            for name in FLOODERS:
                pubs[name].put(status(name))
            next_normal += 1.0
        time.sleep(0.02)
    del keep
    session.close()


# -- the measurement -----------------------------------------------------------------------------------
def median(values: list[float]) -> float:
    s = sorted(values)
    return s[len(s) // 2]


def rss_mb(pid: int) -> float:
    kb = rss_kb(pid)
    if kb is None:
        raise RuntimeError("the console is gone")
    return kb / 1024


def watch(pid: int, seconds: float, every: float) -> list[float]:
    """The console's RSS (MB) every ``every`` s for ``seconds``."""
    out, t0 = [], time.monotonic()
    while time.monotonic() - t0 < seconds:
        out.append(rss_mb(pid))
        time.sleep(every)
    return out


def flood_row() -> str:
    for line in fb.screen().splitlines():
        if line.split()[:1] == ["flood-1"]:
            return " ".join(line.split())
    return ""


def run(args: argparse.Namespace) -> dict:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    pid = fb.start_console(endpoint, (200, 60), args.console_root)
    procs: list[subprocess.Popen] = []
    try:
        time.sleep(1.0)
        procs.append(fb.start_sim(args.robots, endpoint))
        flooder = subprocess.Popen(
            [sys.executable, __file__, "--publish", "--endpoint", endpoint, *pass_on(args)],
            env=fb.env(),
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        procs.append(flooder)
        assert flooder.stdin is not None and flooder.stdout is not None
        flooder.stdout.readline()
        want = args.robots + len(FLOODERS)
        listed = fb.wait(lambda: f"{want} robots" in fb.screen() or f"all {want} alive" in fb.screen(), 60)
        time.sleep(args.warmup)
        before = watch(pid, 5.0, args.every)
        rounds = []
        for _ in range(args.rounds):
            flooder.stdin.write(f"flood {args.flood_seconds}\n")
            flooder.stdin.flush()
            time.sleep(args.flood_seconds / 2)
            row = flood_row()
            during = watch(pid, args.flood_seconds / 2, args.every)
            sent = flooder.stdout.readline().split()[1:]
            after = watch(pid, args.after, args.every)
            rounds.append(
                {
                    "sent_flood_big": [int(v) for v in sent],
                    "flood_row_on_screen": row,
                    "rss_mb_peak_during": round(max(during), 1),
                    "rss_mb_at_end_of_after": round(after[-1], 1),
                    "rss_mb_after_by_10s": [round(v, 1) for v in after[:: max(1, round(10 / args.every))]],
                }
            )
            print(json.dumps(rounds[-1]), flush=True)
        return {
            "robots": want,
            "listed_after_s": None if listed is None else round(listed, 2),
            "rss_mb_before": round(median(before), 1),
            "rounds": rounds,
        }
    finally:
        for p in procs:
            with contextlib.suppress(ProcessLookupError):
                p.kill()
            p.wait()
        fb.tmux("kill-session", "-t", fb.SESSION)


def pass_on(args: argparse.Namespace) -> list[str]:
    return ["--rate", str(args.rate), "--big-rate", str(args.big_rate), "--big-bytes", str(args.big_bytes)]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robots", type=int, default=200, help="simulated robots beside the two (default 200)")
    p.add_argument("--rounds", type=int, default=3, help="floods, each followed by --after s of calm")
    p.add_argument("--flood-seconds", type=float, default=10.0)
    p.add_argument("--rate", type=float, default=1000.0, help="flood-1's valid statuses a second")
    p.add_argument("--big-rate", type=float, default=20.0, help="big-1's oversized payloads a second")
    p.add_argument("--big-bytes", type=int, default=1 << 20, help="each of big-1's payloads (default 1 MiB)")
    p.add_argument("--after", type=float, default=30.0, help="seconds watched after each flood")
    p.add_argument("--warmup", type=float, default=10.0, help="seconds after the rows are listed")
    p.add_argument("--every", type=float, default=1.0, help="seconds between RSS readings")
    p.add_argument("--console-root", type=Path, help="the console's code from this checkout")
    p.add_argument("--publish", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--endpoint", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.publish:
        publish(args.endpoint, args.rate, args.big_rate, args.big_bytes)
        return
    out = run(args)
    settings = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()}
    del settings["publish"], settings["endpoint"]
    emit({"bench": "fleet_flood", **settings, **out})


if __name__ == "__main__":
    with contextlib.suppress(KeyboardInterrupt):
        signal.signal(signal.SIGTERM, lambda *a: sys.exit(1))
        main()
