#!/usr/bin/env python
"""What the console's screen costs a link: the bytes a second ``arbiter-tui`` writes to its terminal, at
80x24 and 200x60, on each screen (1-4), while the robot drives a mission; and what that means on a slow
SSH link (docs/benchmarks/screen-bytes.md).

The console runs in embedded mode (its bundled backend, the simulated robot) in a pseudo-terminal this
script reads (tests/support/ptyterm.py), answering its cursor queries as a terminal does. For each size,
one console: it starts, ``a`` selects go_to_goal; for each screen, ``1`` and ``g`` start the square
afresh (~20 s: it drives through the measurement), the screen is shown, and after ``--settle`` seconds
every byte of ``--seconds`` is counted. A frame is a burst of output (reads less than ``FRAME_GAP_S``
apart).

The model: a link of ``--link-kbit`` kbit/s carries ``C`` bytes a second. A screen writing ``R < C``
leaves a key's echo behind at most the frame in flight: echo ~ (frame p95 + frame p50, the echo's own)
/ C plus the round trip; ``R >= C`` builds a backlog that grows by ``R - C`` each second (every
second's picture later than the last: no bound).

Then, measured behind a link of ``--link-kbit`` (the harness delivers what the console writes at that
rate, after deep buffers as sshd's; the terminal answers a query when it gets there): the control
screen watched for ``--watch`` seconds with no keys (the bytes a second, how far behind the screen is),
then ``--keys`` keys, each timed from the press to its echo on the screen. bench/ssh_link.py measures
the same through a real SSH link in a network namespace.

    python bench/screen_bytes.py                         # both sizes, screens 1-4, 10 s each
    python bench/screen_bytes.py --tui-args=--max-fps=2  # the same with fewer frames
    python bench/screen_bytes.py --pythonpath /path/to/main    # another checkout's console
    python bench/screen_bytes.py --sizes 80x24 --seconds 5
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import emit, pct

from tests.support.ptyterm import PtyTerminal

FRAME_GAP_S = 0.02  # output this close together is one frame
QUERY_BYTES = 8  # the heartbeat's cursor queries (4 bytes each) between frames
SCREENS = {"1": "control", "2": "analytics", "3": "latency", "4": "topics"}


class Frames:
    """The reads' sizes grouped into frames (bursts), timed by the reader's clock."""

    def __init__(self, term: PtyTerminal) -> None:
        self.term = term

    def measure(self, seconds: float) -> dict:
        frames: list[int] = []
        start_bytes, t0 = self.term.bytes, time.monotonic()
        last_bytes, last_change, current = start_bytes, t0, 0
        while (now := time.monotonic()) - t0 < seconds:
            b = self.term.bytes
            if b != last_bytes:
                if now - last_change > FRAME_GAP_S and current:
                    if current > QUERY_BYTES:  # (a cursor query alone is no frame)
                        frames.append(current)
                    current = 0
                current += b - last_bytes
                last_bytes, last_change = b, now
            time.sleep(0.002)
        if current > QUERY_BYTES:
            frames.append(current)
        total = self.term.bytes - start_bytes
        elapsed = time.monotonic() - t0
        return {
            "bytes_per_s": round(total / elapsed),
            "frames_per_s": round(len(frames) / elapsed, 2),
            "frame_p50": pct(frames, 0.5),
            "frame_p95": pct(frames, 0.95),
            "frame_max": max(frames) if frames else 0,
        }


def echo_model(row: dict, link_bytes_s: float, rtt_s: float) -> float | None:
    """A key's echo on a link carrying ``link_bytes_s``: None when the screen outruns the link."""
    if row["bytes_per_s"] >= link_bytes_s:
        return None
    return round(rtt_s + ((row["frame_p95"] or 0) + (row["frame_p50"] or 0)) / link_bytes_s, 3)


def run_size(cols: int, rows: int, args: argparse.Namespace, home: str) -> list[dict]:
    env = {"XDG_DATA_HOME": home, "XDG_CONFIG_HOME": home, "XDG_STATE_HOME": home}
    if args.pythonpath:
        env["PYTHONPATH"] = args.pythonpath
    extra = shlex.split(args.tui_args)
    term = PtyTerminal(["--no-journal", "--log-file", f"{home}/console-{cols}.log", *extra], cols, rows, env)
    out = []
    try:
        deadline = time.monotonic() + 30
        while b" CONNECTED" not in term.output() and time.monotonic() < deadline:
            time.sleep(0.1)
        term.type("a")  # go_to_goal
        frames = Frames(term)
        for key, name in SCREENS.items():
            term.type("1")
            time.sleep(0.3)
            term.type("g")  # the mission afresh for each screen: it drives through the measurement
            time.sleep(0.3)
            term.type(key)
            time.sleep(args.settle)
            row = {"size": f"{cols}x{rows}", "screen": f"{key} {name}", **frames.measure(args.seconds)}
            row["echo_s"] = echo_model(row, args.link_kbit * 1000 / 8, args.rtt_ms / 1000)
            out.append(row)
            print(row, file=sys.stderr, flush=True)
        if args.watch:
            out.append({"size": f"{cols}x{rows}", **watch_through_link(term, args)})
            print(out[-1], file=sys.stderr, flush=True)
        if args.keys:
            out.append({"size": f"{cols}x{rows}", **echo_through_link(term, args)})
            print(out[-1], file=sys.stderr, flush=True)
    finally:
        term.close()
    return out


SPEED = re.compile(rb"speed \d\.\d\d")  # the control screen's max speed, which q and z change


def watch_through_link(term: PtyTerminal, args: argparse.Namespace) -> dict:
    """The control screen, a mission driving, behind the slow link, no keys for ``--watch`` seconds: the
    bytes a second written and how far behind the person's screen is, each second."""
    term.type("1")
    time.sleep(0.3)
    term.type("g")
    term.rate = args.link_kbit * 1000 / 8
    start_bytes, started, backlog = term.bytes, time.monotonic(), []
    for _ in range(int(args.watch)):
        time.sleep(1.0)
        backlog.append(round(term.backlog_s(), 2))
    rate = (term.bytes - start_bytes) / (time.monotonic() - started)
    term.rate = None
    time.sleep(backlog[-1] + 0.5)  # (what the link still holds reaches the screen)
    return {"watched_bytes_per_s": round(rate), "backlog_s_each_second": backlog}


def echo_through_link(term: PtyTerminal, args: argparse.Namespace) -> dict:
    """The control screen, a mission driving, behind a link of ``--link-kbit`` with deep buffers (the
    harness's ``rate``): ``--keys`` presses of q and z, each timed from the key to its echo (the new max
    speed) reaching the screen through the link. The link's own round trip is not in it."""
    term.type("1")
    time.sleep(0.3)
    term.type("g")
    term.rate = args.link_kbit * 1000 / 8
    time.sleep(args.settle + 3)  # the backlog builds, or the console spreads its frames
    echoes: list[float] = []
    start_bytes, started, backlog = term.bytes, time.monotonic(), 0.0
    for i in range(args.keys):
        mark, pressed = term.mark(), time.monotonic()
        term.type("q" if i % 2 == 0 else "z")
        while time.monotonic() - pressed < 10:
            if (hit := SPEED.search(term.since(mark))) is not None:
                echoes.append(term.on_screen_at(mark + hit.end()) - pressed)
                break
            time.sleep(0.005)
        backlog = max(backlog, term.backlog_s())
        time.sleep(0.5)
    rate = (term.bytes - start_bytes) / (time.monotonic() - started)
    term.rate = None
    return {
        "screen": f"1 control, keys through {args.link_kbit:g} kbit/s",
        "echo_p50": pct(echoes, 0.5), "echo_p95": pct(echoes, 0.95), "echo_max": round(max(echoes), 3),
        "echoed": f"{len(echoes)}/{args.keys}", "bytes_per_s": round(rate),
        "backlog_max_s": round(backlog, 2),
    }  # fmt: skip


def table(rows: list[dict], link_kbit: float) -> str:
    lines = [
        f"| size | screen | bytes/s | frames/s | frame p50 / p95 / max (B) | echo at {link_kbit:g} kbit/s |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for r in rows:
        if "frame_p50" not in r:
            continue
        echo = "no bound (backlog)" if r["echo_s"] is None else f"{r['echo_s'] * 1000:.0f} ms"
        lines.append(
            f"| {r['size']} | {r['screen']} | {r['bytes_per_s']} | {r['frames_per_s']} | "
            f"{r['frame_p50']:.0f} / {r['frame_p95']:.0f} / {r['frame_max']} | {echo} |"
        )
    lines += [
        "",
        f"| size | key to echo through {link_kbit:g} kbit/s: p50 / p95 / max | keys echoed | bytes/s "
        "| backlog max |",
        "|---|---:|---:|---:|---:|",
    ]
    for r in rows:
        if "echo_p50" in r:
            lines.append(
                f"| {r['size']} | {r['echo_p50'] * 1000:.0f} / {r['echo_p95'] * 1000:.0f} / "
                f"{r['echo_max'] * 1000:.0f} ms | {r['echoed']} | {r['bytes_per_s']} | "
                f"{r['backlog_max_s']} s |"
            )
    for r in rows:
        if "watched_bytes_per_s" in r:
            lines.append(
                f"\nwatching {r['size']} through {link_kbit:g} kbit/s: {r['watched_bytes_per_s']} bytes/s, "
                f"backlog each second (s): {r['backlog_s_each_second']}"
            )
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="80x24,200x60")
    p.add_argument("--seconds", type=float, default=10.0)
    p.add_argument("--settle", type=float, default=2.0)
    p.add_argument("--link-kbit", type=float, default=256.0)
    p.add_argument("--rtt-ms", type=float, default=60.0, help="the link's round trip for the model")
    p.add_argument(
        "--watch", type=float, default=15.0, help="seconds watched through the slow link (0: none)"
    )
    p.add_argument("--keys", type=int, default=12, help="keys timed through the slow link (0: none)")
    p.add_argument("--pythonpath", help="run the console of another checkout (e.g. /work/main)")
    p.add_argument("--tui-args", default="", help="more arguments for arbiter-tui (one string)")
    args = p.parse_args()
    rows: list[dict] = []
    with tempfile.TemporaryDirectory() as home:
        for size in args.sizes.split(","):
            cols, lines = (int(v) for v in size.split("x"))
            rows += run_size(cols, lines, args, home)
    print(table(rows, args.link_kbit))
    mean = statistics.fmean(r["bytes_per_s"] for r in rows if "frame_p50" in r)
    emit(
        {
            "bench": "screen_bytes",
            "tui_args": args.tui_args,
            "pythonpath": args.pythonpath,
            "rows": rows,
            "mean_bytes_per_s": round(mean),
        }
    )


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    main()
