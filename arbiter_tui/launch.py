"""``arbiter-tui`` (no subcommand): parse flags, start the backend if embedded, run the app."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from arbiter_core import fleet, topics
from arbiter_core.auth import AuthConfigError, load_token
from arbiter_core.cliargs import (
    OneLineParser,
    action_names,
    add_log_level,
    add_version,
    bounded_float,
    count,
    existing_file,
    namespace,
    port,
    positive_float,
    rosbridge_url,
    topic_name,
    tracker_url,
    writable_dir,
)
from arbiter_core.kinematics import DEFAULT_LIMITS
from arbiter_core.logs import default_log_path, log_to_file
from arbiter_core.rosenv import rclpy_missing
from arbiter_core.urls import (
    DEFAULT_ROSBRIDGE,
    UrlError,
    check_token_transport,
    rosbridge_endpoint,
    tracker_beside,
    tracker_endpoint,
)

from .control.stop import NAV2_ACTIONS
from .control.teleop import cap_setting
from .session import config, journal_files
from .session.settings import (
    COLLECTION_RATE_HZ,
    CONNECT,
    EMBEDDED,
    JOURNAL_MAX_MB,
    KEY_TIMEOUT_S,
    MAX_FPS,
    OFFSET_WARN_MS,
    OPERATOR_TIMEOUT_S,
    REPEAT_RATE_HZ,
    SIM,
    Settings,
)

D = Settings()  # the defaults: one place, read by the parser, the help texts and the app
# the observe group's flags only observe mode reads (--stop-actions serves every mode)
OBSERVE_ONLY = ("label", "cmd_topic", "cmd_stamped", "plan_topic", "goal_topic", "status_topic")


def robot_name(text: str) -> str:
    """A robot's name as the fleet spells it (``arbiter_core.fleet.robot_name``)."""
    try:
        return fleet.robot_name(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui",
        description="Teleop console and analytics/latency monitor for ROS 2 robots. With no mode flag it "
        "starts the bundled backend (rosbridge endpoint, latency tracker, simulated robot) on 127.0.0.1 and "
        "drives it. Subcommands: 'arbiter-tui compare [--help]' runs every controller on every mission in "
        "simulated time (behind a modelled link with --latency) and ranks them per mission; 'arbiter-tui "
        "stats FILE|BAG_DIR [--help]' prints the statistics of an export or of a ros2 bag recorded on the "
        "robot; 'arbiter-tui topics [--help]' prints every topic's rate, bandwidth, delay and age as the "
        "backend measures them; 'arbiter-tui autonomy start|stop|status [--help]' starts, stops or asks "
        "about the controller the backend runs on the robot; 'arbiter-tui fleet [--help]' lists every "
        "robot announcing itself on Zenoh and opens the console on one.",
    )
    m = p.add_mutually_exclusive_group()
    m.add_argument(
        "--connect", action="store_true", help="use servers that already run (--rosbridge, --tracker)"
    )
    m.add_argument("--sim", action="store_true", help="client-side simulation: no network, latency N/A")
    p.add_argument(
        "--rosbridge",
        type=rosbridge_url,
        help=f"rosbridge URL, ws:// or wss://, path kept (implies --connect; default {DEFAULT_ROSBRIDGE})",
    )
    p.add_argument(
        "--tracker",
        type=tracker_url,
        help="latency tracker URL, http:// or https:// (implies --connect; default: the rosbridge host, "
        "port 8085)",
    )
    p.add_argument(
        "--namespace",
        type=namespace,
        default="",
        help="the robot's namespace, e.g. /robot1: the stamped-command, report and odometry topics "
        "resolve under it (the embedded backend runs under it too)",
    )
    p.add_argument(
        "--odom-topic",
        type=topic_name,
        default="odom",
        help="nav_msgs/Odometry topic; relative names resolve under --namespace, absolute ones are used "
        "as given (default: odom; a Jazzy diff_drive_controller: diff_drive_controller/odom)",
    )
    obs = p.add_argument_group(
        "observe (docs/analytics.md): analytics of what drives the robot, from its own topics"
    )
    obs.add_argument(
        "--observe",
        action="store_true",
        help="record samples and runs from the robot's odometry, command, plan and goal topics instead of "
        "the console's own driving (a new goal starts a run; reaching it, stopped, completes it)",
    )
    obs.add_argument(
        "--label", default=D.observe_label, help="what drives the robot, e.g. nav2_rpp (default %(default)s)"
    )
    obs.add_argument(
        "--cmd-topic", type=topic_name, default=D.cmd_topic, help="its command (default %(default)s)"
    )
    obs.add_argument(
        "--cmd-stamped", action="store_true", help="the command is TwistStamped (its age is the latency)"
    )
    obs.add_argument(
        "--plan-topic", type=topic_name, default=D.plan_topic, help="nav_msgs/Path (default %(default)s)"
    )
    obs.add_argument(
        "--goal-topic", type=topic_name, default=D.goal_topic, help="PoseStamped goal (default %(default)s)"
    )
    obs.add_argument(
        "--status-topic",
        type=topic_name,
        default=D.status_topic,
        help="action_msgs/GoalStatusArray of the controller's action: a goal that succeeds, aborts or is "
        "cancelled ends its run then (default %(default)s, Nav2's navigator)",
    )
    obs.add_argument(
        "--stop-actions",
        type=action_names,
        default=None,
        help="action servers whose goals a stop key cancels, comma-separated (relative names resolve "
        f"under --namespace; '' none; default in observe mode Nav2's: {', '.join(NAV2_ACTIONS)}; "
        "otherwise none)",
    )
    p.add_argument(
        "--robot-name",
        type=robot_name,
        default=None,
        metavar="NAME",
        help="the robot's name, said first in the status line (arbiter-tui fleet passes the name the "
        "robot announces)",
    )
    p.add_argument(
        "--ca-file",
        type=existing_file,
        help="PEM certificate(s) to trust for wss:// and https:// (a private CA; default: the system's)",
    )
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
        "--export-dir",
        type=writable_dir,
        default=Path("."),
        help="where exports are written: an existing directory you can write to (default: .)",
    )
    p.add_argument(
        "--journal-max-mb",
        type=bounded_float(*JOURNAL_MAX_MB, "MB"),
        default=D.journal_max_mb,
        help=f"the journal: what the console records, written to {journal_files.default_dir()} as it goes "
        "(a dropped link, kill -9 or a power cut loses at most the last second; the next start offers a "
        "session that did not end cleanly, R opens it on screen 2; `arbiter-tui stats FILE` reads it); its "
        "files are kept under this many MB, oldest deleted first (%(default)g)",
    )
    p.add_argument("--no-journal", action="store_true", help="write no journal")
    p.add_argument(
        "--collection-rate",
        type=bounded_float(*COLLECTION_RATE_HZ, "Hz", low_open=True),
        default=D.collection_rate,
        help=f"analytics samples per second, up to {COLLECTION_RATE_HZ[1]:g} ({D.collection_rate:g})",
    )
    p.add_argument(
        "--start-paused",
        action="store_true",
        help="do not record analytics until r is pressed (default: recording from the start; a robot "
        "standing still outside a run adds no samples)",
    )
    p.add_argument(
        "--max-points", type=count, default=D.max_points,
        help=f"analytics ring buffer size ({D.max_points}); run summaries keep all their samples regardless",
    )  # fmt: skip
    p.add_argument(
        "--speed",
        type=positive_float,
        default=D.speed,
        help=f"start max speed of teleop and the controllers, m/s ({D.speed:g}; above the robot's "
        f"{DEFAULT_LIMITS.max_linear:g} it is capped, and said)",
    )
    p.add_argument(
        "--turn",
        type=positive_float,
        default=D.turn,
        help=f"start max turn rate, rad/s ({D.turn:g}; capped at {DEFAULT_LIMITS.max_angular:g})",
    )
    p.add_argument(
        "--repeat-rate",
        type=bounded_float(*REPEAT_RATE_HZ, "Hz"),
        default=D.repeat_rate,
        help=f"commands per second while a key is held or a mission drives, a ceiling "
        f"({REPEAT_RATE_HZ[0]:g}-{REPEAT_RATE_HZ[1]:g}; {D.repeat_rate:g})",
    )
    p.add_argument(
        "--key-timeout",
        type=bounded_float(*KEY_TIMEOUT_S, "s"),
        default=D.key_timeout,
        help=f"the longest a held key moves the robot after its last repeat arrived, s: a fresh press holds "
        f"this long, a repeating key twice the longest gap between its recent repeats, at least 0.25 s "
        f"or this (docs/drive.md, 'Over a jittery link'; {KEY_TIMEOUT_S[0]:g}-{KEY_TIMEOUT_S[1]:g}; "
        f"{D.key_timeout:g})",
    )
    p.add_argument(
        "--max-fps",
        type=bounded_float(*MAX_FPS, "Hz"),
        default=D.ui_rate,
        help=f"frames a second at most, and the analytics, latency and topics panels no more often: fewer "
        f"bytes on a slow link (the console also spreads its frames when the terminal's answers come "
        f"later than 0.3 s; docs/benchmarks/screen-bytes.md; {MAX_FPS[0]:g}-{MAX_FPS[1]:g}; "
        f"{D.ui_rate:g})",
    )
    p.add_argument(
        "--operator-timeout",
        type=bounded_float(*OPERATOR_TIMEOUT_S, "s"),
        default=D.operator_timeout,
        help=f"a mission holds (zero command; g resumes it) when the person's terminal has not answered "
        f"the console's cursor queries for this long, s; 0: never (docs/drive.md, 'An operator who cannot "
        f"see'; {OPERATOR_TIMEOUT_S[0]:g}-{OPERATOR_TIMEOUT_S[1]:g}; {D.operator_timeout:g})",
    )
    p.add_argument(
        "--offset-warn-ms",
        type=bounded_float(*OFFSET_WARN_MS, "ms", low_open=True),
        default=D.offset_warn_ms,
        help=f"warn when the clock offset to the tracker is surely beyond this, ms "
        f"({D.offset_warn_ms:g}, the seed's chrony rule)",
    )
    p.add_argument(
        "--token-file",
        type=existing_file,
        help="--connect: file whose first line is the backend's token (default: $ARBITER_TOKEN), sent as "
        "an Authorization: Bearer header to the rosbridge endpoint and the tracker API",
    )
    p.add_argument(
        "--log-file",
        help=f"the console's log, rotated at 1 MB, 3 kept (default: {default_log_path('arbiter-tui').parent}"
        "/arbiter-tui-<pid>.log); nothing is ever logged to the terminal",
    )
    p.add_argument(
        "--config",
        type=Path,
        help=f"config file (TOML; keys are these long option names, plus theme; flags win; default: "
        f"{config.default_path()})",
    )
    p.add_argument(
        "--print-config", action="store_true", help="print the effective settings and where each came from"
    )
    add_log_level(p)
    add_version(p)
    return p


def parse(argv: list[str]) -> tuple[argparse.Namespace, config.Loaded, set[str]] | int:
    """Defaults, then the config file, then the command line; an int is an exit status."""
    from .shell import themes  # (Textual's theme names: imported from the shell, not from Textual here)

    parser = build_parser()
    early = argparse.ArgumentParser(add_help=False)
    early.add_argument("--config", type=Path)
    known, _ = early.parse_known_args(argv)
    path = known.config or config.default_path()
    try:
        loaded = config.load(path, parser, themes.names())
        if known.config is not None and not loaded.exists:
            raise config.ConfigError(f"config {path}: no such file")
    except config.ConfigError as exc:
        print(f"arbiter-tui: {exc}", file=sys.stderr)
        return 2
    parser.set_defaults(**loaded.values)
    args = parser.parse_args(argv)
    cli = config.given_on_command_line(parser, argv)
    # a mode chosen on the command line wins over one (and its servers) from the file
    if "sim" in cli:
        for dest in ("connect", "rosbridge", "tracker"):
            if dest not in cli and dest in loaded.values:
                setattr(args, dest, False if dest == "connect" else None)
    if "connect" in cli and "sim" not in cli:
        args.sim = False
    if args.print_config:
        print(config.describe(args, parser, loaded, cli))
        return 0
    return args, loaded, cli


def run_app(argv: list[str]) -> int:
    parsed = parse(argv)
    if isinstance(parsed, int):
        return parsed
    args, loaded, cli = parsed
    observing = [f"--{dest.replace('_', '-')}" for dest in OBSERVE_ONLY if dest in cli]
    if observing and not args.observe:  # given on the command line and silently ignored: say so
        print(f"arbiter-tui: {', '.join(observing)}: only with --observe (observe mode)", file=sys.stderr)
        return 2
    # roslibpy/twisted/autobahn must never write to the terminal the TUI owns.
    try:
        log_file = str(log_to_file(args.log_file or default_log_path("arbiter-tui"), args.log_level))
    except OSError as exc:
        print(f"arbiter-tui: --log-file {args.log_file}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    try:
        ns = topics.namespace(args.namespace)
        topics.resolve(args.odom_topic, ns, what="odom-topic")
    except topics.TopicNameError as exc:
        print(f"arbiter-tui: --{exc}", file=sys.stderr)
        return 2
    named = args.rosbridge is not None or args.tracker is not None
    if args.sim and named:
        print("arbiter-tui: --rosbridge/--tracker name servers to drive; not with --sim", file=sys.stderr)
        return 2
    # naming a server means using it: never silently start the bundled simulator instead
    mode = CONNECT if args.connect or named else SIM if args.sim else EMBEDDED
    # the embedded backend on DDS needs rclpy: say how to get it now, not as a console stuck connecting
    if mode == EMBEDDED and args.transport == "ros" and (missing := rclpy_missing()) is not None:
        print(f"arbiter-tui: --transport ros: {missing}", file=sys.stderr)
        return 2
    token = None
    if mode == CONNECT:
        try:
            token = load_token(args.token_file)
            bridge = rosbridge_endpoint(args.rosbridge or DEFAULT_ROSBRIDGE)
            tracker = tracker_endpoint(args.tracker) if args.tracker else tracker_beside(bridge)
            check_token_transport(bridge, "--rosbridge", token)
            check_token_transport(tracker, "--tracker", token)
        except (AuthConfigError, UrlError) as exc:
            print(f"arbiter-tui: {exc}", file=sys.stderr)
            return 2
    speed, speed_note = cap_setting("speed", args.speed, DEFAULT_LIMITS.max_linear, "m/s")
    turn, turn_note = cap_setting("turn", args.turn, DEFAULT_LIMITS.max_angular, "rad/s")
    settings = Settings(
        mode=mode,
        transport=args.transport,
        export_dir=args.export_dir,
        collection_rate=args.collection_rate,
        max_points=args.max_points,
        speed=speed,
        turn=turn,
        repeat_rate=args.repeat_rate,
        key_timeout=args.key_timeout,
        operator_timeout=args.operator_timeout,
        ui_rate=args.max_fps,
        analytics_rate=min(D.analytics_rate, args.max_fps),
        offset_warn_ms=args.offset_warn_ms,
        config_path=loaded.path,
        theme=loaded.theme,
        start_paused=args.start_paused,
        notes=tuple(n for n in (speed_note, turn_note) if n),
        observe=args.observe,
        observe_label=args.label,
        robot_name=args.robot_name or "",
        cmd_topic=args.cmd_topic,
        cmd_stamped=args.cmd_stamped,
        plan_topic=args.plan_topic,
        goal_topic=args.goal_topic,
        status_topic=args.status_topic,
        namespace=ns,
        odom_topic=args.odom_topic,
        stop_actions=args.stop_actions,
        journal_dir=None if args.no_journal else journal_files.default_dir(),
        journal_max_mb=args.journal_max_mb,
    )
    if mode == CONNECT:
        settings.rosbridge_url, settings.tracker_url = bridge.url, tracker.url
    from .shell.app import make_app

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
            args.bridge_port,
            args.api_port,
            log_file=str(Path(log_file).with_suffix(".backend.log")),  # its own file: rotation is per writer
            transport=args.transport,
            extra_args=["--log-level", args.log_level, "--namespace", args.namespace or "/"],
        )
        backend.supervise()
        settings.rosbridge_url = f"ws://127.0.0.1:{backend.bridge_port}"
        settings.tracker_url = f"http://127.0.0.1:{backend.api_port}"
    bridge = rosbridge_endpoint(settings.rosbridge_url)
    try:
        link = RosLink(
            bridge.host,
            bridge.port,
            token=token,
            path=bridge.path,
            secure=bridge.secure,
            ca_file=args.ca_file,
            namespace=topics.namespace(args.namespace),
            odom_topic=args.odom_topic,
        )
        tracker = TrackerClient(settings.tracker_url or "", token=token, ca_file=args.ca_file)
    except BaseException:
        if backend is not None:
            backend.stop()
        raise
    return link, tracker, (backend.stop if backend is not None else lambda: None)
