"""``arbiter-backend``: the latency tracker, robot simulator and rosbridge endpoint in one process."""

from __future__ import annotations

import argparse
import asyncio
import errno
import logging
import signal
import sys

from .cliargs import count, port, positive_float
from .core.kinematics import Limits
from .server import Backend, BackendConfig


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="arbiter-backend",
        description="Latency tracker (HTTP API), differential-drive robot simulator and rosbridge WebSocket "
        "endpoint, in one process with no ROS install. Stops on SIGINT/SIGTERM.",
    )
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default: 127.0.0.1, loopback only)")
    p.add_argument("--bridge-port", type=port, default=9090, help="rosbridge WebSocket port (default: 9090)")
    p.add_argument("--api-port", type=port, default=8085, help="tracker HTTP API port (default: 8085)")
    p.add_argument(
        "--deploy-mode",
        default="native",
        help="label stored in every latency record: native, docker, pi, cloud... (default: native)",
    )
    p.add_argument(
        "--no-sim", action="store_true", help="no simulator: a real robot consumes /cmd_vel_measured"
    )
    p.add_argument(
        "--no-bridge", action="store_true", help="no rosbridge endpoint: another rosbridge server is used"
    )
    p.add_argument("--max-records", type=count, default=10_000, help="latency records kept (default: 10000)")
    p.add_argument(
        "--cmd-timeout",
        type=positive_float,
        default=0.5,
        help="seconds without a command before the robot is stopped (default: 0.5)",
    )
    p.add_argument("--max-linear", type=positive_float, default=1.0, help="linear limit m/s (default: 1.0)")
    p.add_argument(
        "--max-angular", type=positive_float, default=2.0, help="angular limit rad/s (default: 2.0)"
    )
    p.add_argument("--log-file", help="write logs to this file (default: warnings to stderr)")
    return p


async def _run(config: BackendConfig) -> int:
    backend = Backend(config)
    try:
        await backend.start()
    except OSError as exc:
        if exc.errno in (errno.EADDRINUSE, errno.EACCES, errno.EADDRNOTAVAIL):
            print(f"arbiter-backend: cannot listen on {config.host}: {exc.strerror}", file=sys.stderr)
            return 2
        raise
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        loop.add_signal_handler(sig, stop.set)
    print(backend.describe(), flush=True)
    await stop.wait()
    await backend.stop()
    print("arbiter-backend: stopped", flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.log_file:
        logging.basicConfig(
            filename=args.log_file,
            level=logging.INFO,
            format="%(asctime)s %(name)s %(levelname)s %(message)s",
        )
    else:
        logging.basicConfig(level=logging.WARNING, format="arbiter-backend: %(levelname)s %(message)s")
    config = BackendConfig(
        host=args.host,
        bridge_port=args.bridge_port,
        api_port=args.api_port,
        deploy_mode=args.deploy_mode,
        sim=not args.no_sim,
        bridge=not args.no_bridge,
        max_records=args.max_records,
        cmd_timeout=args.cmd_timeout,
        limits=Limits(max_linear=args.max_linear, max_angular=args.max_angular),
    )
    try:
        return asyncio.run(_run(config))
    except KeyboardInterrupt:
        return 0


if __name__ == "__main__":
    sys.exit(main())
