"""``arbiter-tui autonomy start|stop|status``: the robot-side controller (``arbiter-backend --autonomy``),
started and stopped from the console's machine through ``/api/autonomy``.

Exit 0 with the state on one line (``--json``: the API's answer); 1 when the backend refused (its reason
on stderr: autonomy off, a bad name, no odometry yet); 2 on bad arguments; 3 when it cannot be asked.
"""

from __future__ import annotations

import argparse
import json
import ssl
import sys
from typing import Any

from arbiter_core.auth import AuthConfigError
from arbiter_core.cliargs import OneLineParser
from arbiter_core.controllers import CONTROLLERS, MISSIONS
from arbiter_core.urls import UrlError

from . import tracker_args


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui autonomy",
        description="Start, stop or ask about the controller the backend runs on the robot "
        "(arbiter-backend --autonomy; grade it with arbiter-tui --observe).",
    )
    p.add_argument("action", choices=("start", "stop", "status"))
    p.add_argument("algorithm", nargs="?", choices=CONTROLLERS, help="start: the controller")
    p.add_argument("--mission", default="square", choices=tuple(MISSIONS), help="start: default square")
    p.add_argument("--speed", type=float, default=0.5, help="start: m/s cap (default 0.5)")
    p.add_argument("--turn", type=float, default=1.0, help="start: rad/s cap (default 1.0)")
    p.add_argument("--json", action="store_true", help="print the API's answer as JSON")
    tracker_args.add(p)
    return p


def line(state: dict[str, Any]) -> str:
    if state.get("algorithm") is None:
        return f"autonomy: {state.get('state')}"
    where = f"waypoint {state.get('waypoint')}/{state.get('waypoints')}"
    final = state.get("final_error_m")
    tail = "" if final is None else f", final error {final:.3f} m"
    return (f"autonomy: {state.get('state')} · {state['algorithm']} on {state.get('mission')} · {where} · "
            f"{state.get('commands')} commands{tail}")  # fmt: skip


def run(argv: list[str]) -> int:
    p = build_parser()
    args = p.parse_args(argv)
    if args.action == "start" and args.algorithm is None:
        p.error(f"start needs an algorithm: {', '.join(CONTROLLERS)}")
    try:
        endpoint, token = (tracker := tracker_args.checked(args)).endpoint, tracker.token
    except (ValueError, AuthConfigError, UrlError) as exc:
        print(f"arbiter-tui autonomy: {exc}", file=sys.stderr)
        return 2
    import httpx

    url = f"{endpoint.url.rstrip('/')}/api/autonomy"
    method = {"start": "POST", "stop": "DELETE", "status": "GET"}[args.action]
    body = None
    if args.action == "start":
        body = {"algorithm": args.algorithm, "mission": args.mission, "speed": args.speed, "turn": args.turn}
    # https:// verified against the system's CAs, or against --ca-file (a private CA), as the console
    verify: Any = True if args.ca_file is None else ssl.create_default_context(cafile=str(args.ca_file))
    headers = {} if token is None else {"Authorization": f"Bearer {token}"}
    try:
        resp = httpx.request(method, url, json=body, headers=headers, timeout=args.timeout, verify=verify)
        answer = resp.json()
    except (httpx.HTTPError, ValueError) as exc:
        print(f"arbiter-tui autonomy: {url}: {exc or type(exc).__name__}", file=sys.stderr)
        return 3
    if resp.status_code >= 400 or not isinstance(answer, dict):
        why = answer.get("error") if isinstance(answer, dict) else None
        print(f"arbiter-tui autonomy: {url}: {resp.status_code} {why or resp.text[:200]}", file=sys.stderr)
        return 1
    print(json.dumps(answer) if args.json else line(answer))
    return 0
