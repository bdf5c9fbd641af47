"""``arbiter-tui fleet``: one row per robot that announces itself on Zenoh (``arbiter-backend --zenoh``).

The screen by default; ``--json`` prints the same rows once, for scripts and CI; ``--history NAME``
prints a robot's answer to its history queryable. Exit 2 on bad arguments (and without Zenoh, or with a
config file Zenoh does not take), 3 when the session cannot be opened (the router unreachable within
``--wait``, a port that cannot be listened on).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

from arbiter_core import fleet
from arbiter_core.cliargs import OneLineParser, bounded_float, existing_file

from .client import ConsoleSettings, FleetClient, FleetUnavailable
from .rows import STALE_AFTER_S, FleetModel, FleetView

DEFAULT_ROUTER = "tcp/127.0.0.1:7447"


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui fleet",
        description="One row per robot announcing itself on Zenoh (arbiter-backend --zenoh): alive, stale "
        "or lost (never dropped; unknown while this console's own link is down), who drives, latency p95, "
        "clock offset bound, worst topic, controller and its last run, sorted by severity, the worst in "
        "sight. Enter opens the single-robot console on the selected robot; space stops it (its backend "
        "answers what it stopped; the router's access control says who may).",
    )
    p.add_argument(
        "--connect",
        metavar="ENDPOINT[,...]",
        help=f"the site's Zenoh router (default {DEFAULT_ROUTER}, unless --listen)",
    )
    p.add_argument(
        "--listen",
        metavar="ENDPOINT[,...]",
        help="be the site's router: robots connect here, e.g. tcp/0.0.0.0:7447 (with --connect too: "
        "also join that router)",
    )
    p.add_argument(
        "--zenoh-config",
        type=existing_file,
        metavar="FILE",
        help="a Zenoh config file (JSON5): user/password, TLS files, and as the router its access control",
    )
    p.add_argument(
        "--filter", default="", metavar="GLOB", help="only robots whose name matches, e.g. 'lab-*'"
    )
    p.add_argument("--json", action="store_true", help="print the rows once as JSON and exit")
    p.add_argument(
        "--wait",
        type=bounded_float(0.0, 600.0, "s"),
        default=3.0,
        metavar="S",
        help="with --json or --history: how long to wait for the router and the robots' figures (default 3)",
    )
    p.add_argument("--history", metavar="NAME", help="print this robot's history answer as JSON and exit")
    p.add_argument(
        "--minutes",
        type=bounded_float(0.0, fleet.HISTORY_MINUTES, "min", low_open=True),
        default=fleet.HISTORY_MINUTES,
        help=f"with --history: the last N minutes (default and most: {fleet.HISTORY_MINUTES:g})",
    )
    p.add_argument(
        "--stale-after",
        type=bounded_float(1.0, 3600.0, "s"),
        default=STALE_AFTER_S,
        metavar="S",
        help=f"a robot with no status this long reads 'stale' (default {STALE_AFTER_S:g})",
    )
    p.add_argument(
        "--bell",
        action="store_true",
        help="ring the terminal's bell when a robot goes lost (it is said on the screen once either way)",
    )
    p.add_argument(
        "--token-file",
        type=existing_file,
        help="passed to the console Enter opens, for a robot that wants one",
    )
    p.add_argument(
        "--ca-file", type=existing_file, help="passed to the console Enter opens (wss://, https://)"
    )
    return p


def _settings(args: argparse.Namespace) -> ConsoleSettings:
    connect = fleet.parse_endpoints(args.connect) if args.connect else ()
    listen = fleet.parse_endpoints(args.listen) if args.listen else ()
    if not connect and not listen:
        connect = (DEFAULT_ROUTER,)
    return ConsoleSettings(connect=connect, listen=listen, config_file=args.zenoh_config)


def _complete(view: FleetView) -> bool:
    """Every robot with a token has sent its status and latency (what a row is made of)."""
    return all(r.state == "lost" or (r.driver is not None and r.latency_count is not None) for r in view.rows)


def run(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    try:
        settings = _settings(args)
        if args.history is not None:
            fleet.robot_name(args.history)
    except ValueError as exc:
        flag = "--history" if "robot name" in str(exc) else "--connect/--listen"
        print(f"arbiter-tui fleet: {flag}: {exc}", file=sys.stderr)
        return 2
    try:
        client = FleetClient(settings, FleetModel(stale_after=args.stale_after))
    except FleetUnavailable as exc:  # Zenoh not installed, a config file Zenoh does not take
        print(f"arbiter-tui fleet: {exc}", file=sys.stderr)
        return 2
    try:
        if args.json or args.history is not None:
            client.open(connect_timeout_ms=max(1, round(args.wait * 1000)))
        elif settings.listen:
            client.open()  # as the router: a port that cannot be listened on stops it here, in one line
    except FleetUnavailable as exc:
        print(f"arbiter-tui fleet: {exc}", file=sys.stderr)
        return 3
    try:
        if args.history is not None:
            return _print_history(client, args.history, args.minutes)
        if args.json:
            return _print_rows(client, args.filter, args.wait)
        return _screen(client, args)
    finally:
        client.close()


def _print_rows(client: FleetClient, pattern: str, wait: float) -> int:
    deadline = time.monotonic() + wait
    time.sleep(min(0.5, wait))  # the tokens already there, and a status period
    view = client.view(pattern)
    # as the router, robots connect at their own pace (their retry period): the whole wait; as a
    # client, the router already knows them: until every row has its figures
    early = not client.settings.listen
    while (
        not (early and view.rows and _complete(view) and not client.pending()) and time.monotonic() < deadline
    ):
        time.sleep(0.1)
        view = client.view(pattern)
    print(json.dumps(view.to_json()))
    return 0


def _print_history(client: FleetClient, name: str, minutes: float) -> int:
    answer = client.history(name, minutes)
    if isinstance(answer, str):
        print(f"arbiter-tui fleet: {answer}", file=sys.stderr)
        return 1
    print(json.dumps(fleet.to_obj(answer)))
    return 0


def open_console(argv: list[str]) -> int:
    """The single-robot console, as ``arbiter-tui --rosbridge URL --tracker URL`` runs it, in this
    terminal; the fleet comes back when it quits."""
    return subprocess.run([sys.executable, "-m", "arbiter_tui.cli", *argv], check=False).returncode


def _screen(client: FleetClient, args: argparse.Namespace) -> int:
    from .app import FleetApp

    if not client.opened.is_set():
        client.open_in_background()  # a client waits for its router on a thread; the screen says so
    app = FleetApp(
        source=client.view,
        history=client.history,
        stop=client.stop,
        bell_on_lost=args.bell,
        opener=open_console,
        pattern=args.filter,
        token_file=None if args.token_file is None else str(Path(args.token_file)),
        ca_file=None if args.ca_file is None else str(Path(args.ca_file)),
    )
    app.run()
    return 0
