"""``arbiter-tui`` (no subcommand): parse flags, start the backend if embedded, run the app."""

from __future__ import annotations

import argparse
import logging
import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

from arbiter_core.auth import AuthConfigError, load_token
from arbiter_core.cliargs import OneLineParser, count, port, positive_float

from .settings import CONNECT, EMBEDDED, SIM, Settings


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui",
        description="Teleop console and analytics/latency monitor for ROS 2 robots. With no mode flag it "
        "starts the bundled backend (rosbridge endpoint, latency tracker, simulated robot) on 127.0.0.1 and "
        "drives it. 'arbiter-tui stats FILE' prints the statistics of an export.",
    )
    m = p.add_mutually_exclusive_group()
    m.add_argument(
        "--connect", action="store_true", help="use servers that already run (--rosbridge, --tracker)"
    )
    m.add_argument("--sim", action="store_true", help="client-side simulation: no network, latency N/A")
    p.add_argument("--rosbridge", default="ws://127.0.0.1:9090", help="rosbridge URL for --connect")
    p.add_argument("--tracker", default="http://127.0.0.1:8085", help="latency tracker URL for --connect")
    p.add_argument(
        "--bridge-port", type=port, default=9090, help="embedded: rosbridge port (a free one if taken)"
    )
    p.add_argument(
        "--api-port", type=port, default=8085, help="embedded: tracker API port (a free one if taken)"
    )
    p.add_argument(
        "--transport",
        choices=("embedded", "ros"),
        default="embedded",
        help="embedded mode: the backend's transport; ros runs its nodes on DDS (needs the [ros] extra)",
    )
    p.add_argument(
        "--export-dir", type=Path, default=Path("."), help="where exports are written (default: .)"
    )
    p.add_argument(
        "--collection-rate", type=positive_float, default=10.0, help="analytics samples per second (10)"
    )
    p.add_argument("--max-points", type=count, default=1000, help="analytics ring buffer size (1000)")
    p.add_argument("--speed", type=positive_float, default=0.5, help="teleop start speed, m/s (0.5)")
    p.add_argument("--turn", type=positive_float, default=1.0, help="teleop start turn rate, rad/s (1.0)")
    p.add_argument(
        "--repeat-rate",
        type=positive_float,
        default=10.0,
        help="commands per second while a key is held (10)",
    )
    p.add_argument(
        "--key-timeout", type=positive_float, default=0.6, help="stop this long after the last key, s (0.6)"
    )
    p.add_argument(
        "--offset-warn-ms",
        type=positive_float,
        default=10.0,
        help="warn when the clock offset to the tracker exceeds this, ms (10, the seed's chrony rule)",
    )
    p.add_argument(
        "--token-file",
        type=Path,
        help="--connect: file whose first line is the backend's token (default: $ARBITER_TOKEN), sent as "
        "an Authorization: Bearer header to the rosbridge endpoint and the tracker API",
    )
    p.add_argument(
        "--log-file", help="log file for the client libraries (default: a file in the temp directory)"
    )
    return p


def _host_port(url: str, default_port: int) -> tuple[str, int]:
    u = urlparse(url)
    if u.scheme not in ("ws", "wss") or not u.hostname:
        raise ValueError(f"--rosbridge must be a ws:// URL, got {url!r}")
    return u.hostname, u.port or default_port


def run_app(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    log_file = args.log_file or os.path.join(tempfile.gettempdir(), "arbiter-tui.log")
    # roslibpy/twisted/autobahn must never write to the terminal the TUI owns.
    logging.basicConfig(
        filename=log_file, level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s"
    )
    if not args.export_dir.is_dir():
        print(f"arbiter-tui: --export-dir {args.export_dir} is not a directory", file=sys.stderr)
        return 2
    mode = CONNECT if args.connect else SIM if args.sim else EMBEDDED
    token = None
    if mode == CONNECT:
        try:
            token = load_token(args.token_file)
        except AuthConfigError as exc:
            print(f"arbiter-tui: {exc}", file=sys.stderr)
            return 2
    settings = Settings(
        mode=mode,
        transport=args.transport,
        export_dir=args.export_dir,
        collection_rate=args.collection_rate,
        max_points=args.max_points,
        speed=args.speed,
        turn=args.turn,
        repeat_rate=args.repeat_rate,
        key_timeout=args.key_timeout,
        offset_warn_ms=args.offset_warn_ms,
    )
    if mode == CONNECT:
        try:
            _host_port(args.rosbridge, 9090)
        except ValueError as exc:
            print(f"arbiter-tui: {exc}", file=sys.stderr)
            return 2
        settings.rosbridge_url = args.rosbridge
        settings.tracker_url = args.tracker
    from .app import make_app

    if mode == SIM:
        from .link.sim import SimLink

        app = make_app(settings, SimLink())
    else:
        app = make_app(settings, connector=lambda: _connect(args, settings, token, log_file))
    try:
        app.run()
    finally:
        app.close_link()
    return 0


def _connect(
    args: argparse.Namespace, settings: Settings, token: str | None, log_file: str
) -> tuple[Any, Any, Callable[[], None]]:
    """Runs in the app's worker thread once the first frame is on screen: start the embedded backend
    (embedded mode), then the rosbridge link and the tracker poller. Raises with a one-line reason."""
    from .latency.tracker_client import TrackerClient
    from .link.rosbridge import RosLink

    backend = None
    if settings.mode == EMBEDDED:
        from .link.embedded import EmbeddedBackend

        backend = EmbeddedBackend.start(
            args.bridge_port, args.api_port, log_file=log_file, transport=args.transport
        )
        backend.supervise()
        host, port = "127.0.0.1", backend.bridge_port
        settings.rosbridge_url = f"ws://{host}:{port}"
        settings.tracker_url = f"http://127.0.0.1:{backend.api_port}"
    else:
        host, port = _host_port(args.rosbridge, 9090)
    try:
        link = RosLink(host, port, token=token)
        tracker = TrackerClient(settings.tracker_url or "", token=token)
    except BaseException:
        if backend is not None:
            backend.stop()
        raise
    return link, tracker, (backend.stop if backend is not None else lambda: None)
