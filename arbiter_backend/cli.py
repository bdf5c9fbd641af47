"""``arbiter-backend``: the latency tracker, robot simulator and rosbridge endpoint in one process."""

from __future__ import annotations

import argparse
import asyncio
import errno
import logging
import os
import signal
import ssl
import sys
from collections.abc import Callable, Coroutine
from pathlib import Path
from typing import TYPE_CHECKING, Any

from arbiter_core import auth, topics
from arbiter_core import fleet as fleet_core
from arbiter_core.cliargs import (
    OneLineParser,
    add_log_level,
    add_version,
    count,
    non_negative_float,
    port,
    positive_float,
)
from arbiter_core.kinematics import Limits
from arbiter_core.logs import log_to_file
from arbiter_core.rosenv import rclpy_missing
from arbiter_core.topics import MEASURED_TYPES
from arbiter_core.topicstats import WINDOW_S

from . import supervise
from .bridge import DEAD_AFTER, MAX_FRAME_BYTES, TRANSPORT_MAX_FRAME, WS_PING_S
from .config import BackendConfig
from .pacing import WAIT_S as PACED_WAIT_S
from .server import Backend

if TYPE_CHECKING:
    from .fleet import FleetSettings
    from .ros.backend import RosBackend as RosBackendT


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-backend",
        description="Latency tracker (HTTP API), differential-drive robot simulator and rosbridge WebSocket "
        "endpoint, in one process with no ROS install. Stops on SIGINT/SIGTERM.",
    )
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to bind (default: 127.0.0.1, loopback only; others need --allow-remote and a token)",
    )
    p.add_argument(
        "--allow-remote",
        action="store_true",
        help="allow --host to be a non-loopback address; clients must then present the token "
        f"(${auth.TOKEN_ENV} or --token-file). An SSH tunnel is the better choice",
    )
    p.add_argument(
        "--token-file",
        type=Path,
        help=f"file whose first line is the shared token (default: ${auth.TOKEN_ENV}); when a token is set "
        "every client must present it: rosbridge 'auth' op, ?token= or Authorization: Bearer",
    )
    p.add_argument(
        "--namespace",
        default="",
        help="put every node and topic under this namespace, e.g. /robot1 (as --ros-args -r __ns:=/robot1; "
        "names stay relative, so --ros-args -r remaps work; a rosbridge client's relative names resolve "
        "under it, as rosbridge's)",
    )
    p.add_argument(
        "--tls-cert",
        type=Path,
        help="PEM certificate (chain): serve wss:// and https:// instead of ws:// and http://",
    )
    p.add_argument("--tls-key", type=Path, help="PEM private key of --tls-cert (if not in the same file)")
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
        "--autonomy",
        action="store_true",
        help="let POST /api/autonomy start a controller on the robot (the seed's behaviour node: "
        "a mission on the odometry, publishing plan, goal_pose and stamped commands; both "
        "transports); off by default: nothing that moves the robot is reachable unless allowed",
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
    p.add_argument(
        "--max-linear-accel",
        type=positive_float,
        default=2.0,
        help="speed-up limit m/s² for forwarded commands; slowing down is never limited (default: 2.0)",
    )
    p.add_argument(
        "--max-angular-accel",
        type=positive_float,
        default=6.0,
        help="speed-up limit rad/s² for forwarded commands (default: 6.0)",
    )
    p.add_argument(
        "--max-command-age",
        type=non_negative_float,
        default=300.0,
        metavar="MS",
        help="drop (count, never forward) commands older than this on arrival, judged with the sender's "
        "clock-offset estimate when it sends one; 0 turns it off (default: 300)",
    )
    p.add_argument(
        "--transport",
        choices=("embedded", "ros"),
        default="embedded",
        help="embedded: in-process topic bus, no ROS needed (default); ros: the tracker and simulator as "
        "rclpy nodes on DDS (needs the [ros] extra or a sourced ROS 2), the endpoint relays to DDS",
    )
    p.add_argument(
        "--measured-type",
        choices=tuple(MEASURED_TYPES),
        default="twist",
        help="type of /cmd_vel_measured: twist (geometry_msgs/Twist, default) or twist_stamped "
        "(TwistStamped with the tracker's receive time, for Jazzy+ diff_drive_controller)",
    )
    p.add_argument(
        "--topics",
        metavar="GLOBS",
        help="topics GET /api/topics measures: comma-separated globs, e.g. '/scan,/odom,/camera/*' "
        "(default: every topic)",
    )
    p.add_argument(
        "--topics-exclude", metavar="GLOBS", help="topics not to measure, e.g. '/rosout,/parameter_events'"
    )
    p.add_argument(
        "--topics-window",
        type=positive_float,
        default=WINDOW_S,
        metavar="S",
        help=f"the sliding window of /api/topics' rates, bandwidths and delays (default: {WINDOW_S:g} s)",
    )
    p.add_argument(
        "--topics-glob",
        metavar="GLOBS",
        help="the only topics a rosbridge client may subscribe, publish or advertise, and that rosapi lists: "
        "comma-separated globs, e.g. '/odom,/scan,/camera/*' (rosbridge_server's topics_glob; default: all)",
    )
    p.add_argument(
        "--services-glob",
        metavar="GLOBS",
        help="the only services a rosbridge client may call (rosapi's own excepted) and that rosapi lists, "
        "e.g. '/arbiter/*' (rosbridge_server's services_glob; default: all). Keep services that move the "
        "robot out unless the operator means clients to reach them",
    )
    p.add_argument(
        "--actions-glob",
        metavar="GLOBS",
        help="the only actions a rosbridge client may send goals to (send_action_goal) or provide "
        "(advertise_action), e.g. '/arm/*' (default: all; rosbridge_server has no such launch "
        "parameter). Keep actions that move the robot out unless the operator means clients to reach them",
    )
    p.add_argument(
        "--params-glob",
        metavar="GLOBS",
        help="the only parameters rosapi's get/set/has/delete_param and get_param_names reach, by name "
        "(the part after '<node>:'), e.g. 'max_*,use_sim_time' (rosbridge_server's params_glob; "
        "default: all)",
    )
    p.add_argument(
        "--ws-ping",
        type=non_negative_float,
        default=WS_PING_S,
        metavar="SECONDS",
        help="ping a WebSocket client silent this long, and drop it after "
        f"{DEAD_AFTER} times as long without a word (0: never; default: {WS_PING_S:g}, "
        "so a client that stops reading for 10 s is kept)",
    )
    p.add_argument(
        "--paced-wait-ms",
        type=non_negative_float,
        default=PACED_WAIT_S * 1000,
        metavar="MS",
        help="to a client that reads slower than its topics bring, send a big frame (a camera image "
        "without fragment_size) only as often as keeps the messages behind it from waiting longer "
        f"than this 97.5 %% of the time (0: send as many as it reads; default: {PACED_WAIT_S * 1000:g})",
    )
    p.add_argument(
        "--max-frame",
        type=lambda text: count(text, TRANSPORT_MAX_FRAME),
        default=MAX_FRAME_BYTES,
        metavar="BYTES",
        help="largest frame a client may send (a camera frame published over the bridge: 640x480 rgb8 is "
        f"1.2 MB as JSON); larger ones get a status error (default: {MAX_FRAME_BYTES}, "
        f"at most {TRANSPORT_MAX_FRAME})",
    )
    add_fleet_arguments(p)
    p.add_argument("--log-file", help="write logs to this file, rotated at 1 MB, 3 kept (default: stderr)")
    add_log_level(p)
    add_version(p)
    p.epilog = (
        "In ROS mode, arguments after --ros-args go to rclpy: e.g. --ros-args -p deploy_mode:=pi "
        "-r __ns:=/robot1. Parameters override the flags. GET /api/health lists the backend's workers; "
        "ARBITER_FAULT=NAME[@SECONDS][*TIMES] makes one fail, to drill a restart (docs/robot.md)."
    )
    return p


def lease_ms(text: str) -> int:
    value = count(text, 60_000)
    if value < 200:
        raise argparse.ArgumentTypeError(f"must be between 200 and 60000, got {value}")
    return value


FLEET_FLAGS = ("zenoh", "robot_name", "zenoh_config", "expect", "advertise_host")


def add_fleet_arguments(p: argparse.ArgumentParser) -> None:
    """``--zenoh`` and its companions (docs/fleet.md); checked by ``fleet.py``."""
    g = p.add_argument_group("fleet: announce this robot to fleet consoles over Zenoh (the [fleet] extra)")
    g.add_argument(
        "--zenoh",
        metavar="ENDPOINT[,...]",
        help="the Zenoh router(s) to announce to, e.g. tcp/192.168.1.10:7447 or tls/router.lan:7447: a "
        "liveliness token and status, latency, topics and runs payloads under arbiter/<name>/, at most "
        f"{fleet_core.BOUND_BYTES_PER_S} payload bytes/s, and a history queryable",
    )
    g.add_argument(
        "--robot-name",
        metavar="NAME",
        help="the name in its keys (letters, digits, _ . -; default: the namespace, else the host name)",
    )
    g.add_argument("--zenoh-mode", choices=("client", "peer"), default="client", help="(default: client)")
    g.add_argument(
        "--zenoh-lease",
        type=lease_ms,
        default=fleet_core.DEFAULT_LEASE_MS,
        metavar="MS",
        help="the liveliness lease this robot announces: its router drops it (consoles read 'lost') this "
        f"long after it goes silent (default: {fleet_core.DEFAULT_LEASE_MS})",
    )
    g.add_argument(
        "--zenoh-config",
        type=Path,
        metavar="FILE",
        help="a Zenoh config file (JSON5) for what the flags do not set: user/password, TLS certificates",
    )
    g.add_argument(
        "--expect",
        metavar="TOPIC>=HZ,...",
        help="the rates the topics payload judges each topic against, e.g. '/scan>=9.5,/odom>=45'",
    )
    g.add_argument(
        "--advertise-host",
        metavar="HOST",
        help="the host in the URLs consoles open (default: --host; this host's name for 0.0.0.0)",
    )


def split_ros_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """``[... --ros-args X Y]`` -> (our arguments, ["--ros-args", X, Y])."""
    if "--ros-args" in argv:
        i = argv.index("--ros-args")
        return argv[:i], argv[i:]
    return argv, []


def make_backend(config: BackendConfig, ros_args: list[str]) -> Backend | RosBackendT:
    try:  # the failures asked of the workers (docs/topics.md), checked before anything starts
        supervise.parse_faults(os.environ.get(supervise.FAULT_ENV))
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if config.transport != "ros":
        if ros_args:
            raise UsageError("--ros-args needs --transport ros")
        return Backend(config)
    missing = rclpy_missing()
    if missing is not None:
        raise UsageError(missing)
    from .ros.backend import RosBackend
    from .ros.nodes import ParameterError

    try:
        return RosBackend(config, ros_args)
    except (ParameterError, ValueError, TypeError) as exc:  # rclpy's parameter type errors are ValueErrors
        raise UsageError(str(exc).splitlines()[0] if str(exc) else type(exc).__name__) from None


class UsageError(Exception):
    pass


async def _run(config: BackendConfig, ros_args: list[str], fleet: FleetSettings | None = None) -> int:
    link = None
    if fleet is not None:
        from .fleet import FleetConfigError, FleetLink

        try:
            link = FleetLink(fleet)  # Zenoh and its config checked before anything starts
        except FleetConfigError as exc:
            print(f"arbiter-backend: {exc}", file=sys.stderr)
            return 2
    try:
        backend = make_backend(config, ros_args)
    except UsageError as exc:
        print(f"arbiter-backend: {exc}", file=sys.stderr)
        return 2
    if link is not None:
        backend.fleet_health = link.health.to_dict  # /api/health's fleet key
    try:
        await backend.start()
    except auth.AuthConfigError as exc:
        await backend.stop()
        print(f"arbiter-backend: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        await backend.stop()
        if exc.errno in (errno.EADDRINUSE, errno.EACCES, errno.EADDRNOTAVAIL):
            print(f"arbiter-backend: cannot listen on {backend.config.host}: {exc.strerror}", file=sys.stderr)
            return 2
        raise
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        loop.add_signal_handler(sig, stop.set)
    announcer = None
    if link is not None and fleet is not None:
        from .fleet import FleetAnnouncer

        announcer = FleetAnnouncer(backend, fleet, link)
        announcer.start()
    print(backend.describe(), flush=True)
    if fleet is not None:
        where = ",".join(fleet.endpoints)
        print(
            f"arbiter-backend: fleet: announcing as {fleet.name} to {where} (Zenoh {fleet.mode})", flush=True
        )
    await stop.wait()
    if announcer is not None:
        await announcer.stop()
    await backend.stop()
    print("arbiter-backend: stopped", flush=True)
    return 0


def _event_loop_runner() -> Callable[[Coroutine[Any, Any, int]], int]:
    """uvloop where it is installed (about 70 µs less per command on a small machine), else asyncio."""
    try:
        import uvloop
    except ImportError:
        return asyncio.run
    run: Callable[[Coroutine[Any, Any, int]], int] = uvloop.run  # typed here even where uvloop is Any
    return run


class _BadRequestFilter(logging.Filter):
    """aiohttp logs every malformed request from a client as an ERROR with a traceback; it has
    already answered 400. One short line is enough, so garbage cannot flood the log."""

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        from aiohttp.http_exceptions import HttpProcessingError

        if isinstance(exc, HttpProcessingError):
            record.levelno, record.levelname = logging.INFO, "INFO"
            record.msg, record.args, record.exc_info, record.exc_text = (
                "bad request answered with %s: %s",
                (exc.code, str(exc.message).splitlines()[0][:120] if exc.message else ""),
                None,
                None,
            )
            return logging.getLogger().isEnabledFor(logging.INFO)
        return True


def main(argv: list[str] | None = None) -> int:
    ours, ros_args = split_ros_args(sys.argv[1:] if argv is None else list(argv))
    args = build_parser().parse_args(ours)
    if args.log_file:
        log_to_file(args.log_file, args.log_level)
    else:
        logging.basicConfig(level=args.log_level, format="arbiter-backend: %(levelname)s %(message)s")
    logging.getLogger("aiohttp.server").addFilter(_BadRequestFilter())
    try:
        token = auth.load_token(args.token_file)
    except auth.AuthConfigError as exc:
        print(f"arbiter-backend: {exc}", file=sys.stderr)
        return 2
    try:
        ns = topics.namespace(args.namespace)
    except topics.TopicNameError as exc:
        print(f"arbiter-backend: --{exc}", file=sys.stderr)
        return 2
    fleet = None
    if any(getattr(args, flag) is not None for flag in FLEET_FLAGS):
        from .fleet import FleetConfigError, settings_from_args

        try:
            fleet = settings_from_args(args, ns)
        except FleetConfigError as exc:
            print(f"arbiter-backend: {exc}", file=sys.stderr)
            return 2
    if args.tls_key is not None and args.tls_cert is None:
        print("arbiter-backend: --tls-key needs --tls-cert", file=sys.stderr)
        return 2
    config = BackendConfig(
        host=args.host,
        allow_remote=args.allow_remote,
        tls_cert=args.tls_cert,
        tls_key=args.tls_key,
        namespace=ns,
        token=token,
        bridge_port=args.bridge_port,
        api_port=args.api_port,
        deploy_mode=args.deploy_mode,
        sim=not args.no_sim,
        bridge=not args.no_bridge,
        autonomy=args.autonomy,
        max_records=args.max_records,
        cmd_timeout=args.cmd_timeout,
        max_command_age_ms=args.max_command_age,
        limits=Limits(
            max_linear=args.max_linear,
            max_angular=args.max_angular,
            max_linear_accel=args.max_linear_accel,
            max_angular_accel=args.max_angular_accel,
        ),
        measured_type=args.measured_type,
        transport=args.transport,
        topics_include=args.topics,
        topics_exclude=args.topics_exclude,
        topics_window=args.topics_window,
        ws_ping=args.ws_ping,
        paced_wait=args.paced_wait_ms / 1000,
        topics_glob=args.topics_glob,
        services_glob=args.services_glob,
        actions_glob=args.actions_glob,
        params_glob=args.params_glob,
        max_frame=args.max_frame,
    )
    try:
        config.ssl_context()
    except (OSError, ssl.SSLError) as exc:
        print(f"arbiter-backend: cannot use --tls-cert/--tls-key: {exc}", file=sys.stderr)
        return 2
    try:
        return _event_loop_runner()(_run(config, ros_args, fleet))
    except KeyboardInterrupt:
        return 0


if __name__ == "__main__":
    sys.exit(main())
