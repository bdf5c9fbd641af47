"""What the command line decides, in one object the app factory takes."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

EMBEDDED = "embedded"
CONNECT = "connect"
SIM = "sim"

# Bounds of the console's numeric settings (flags and config keys alike), checked at start with a one-line
# error. A key held within --key-timeout repeats at --repeat-rate; the rate is a ceiling on commands sent.
COLLECTION_RATE_HZ = (0.0, 100.0)  # (low exclusive, high]: more than 100 samples/s says nothing new
REPEAT_RATE_HZ = (2.0, 50.0)  # at least 2 Hz, so a held key refreshes the 0.5 s deadman in time
KEY_TIMEOUT_S = (0.1, 2.0)  # more than a few seconds would drive on long after the finger left the key
OFFSET_WARN_MS = (0.0, 60_000.0)  # (low exclusive, high]
MAX_FPS = (0.2, 30.0)  # --max-fps: the frames a second (ui_rate) a slow link can ask for
OPERATOR_TIMEOUT_S = (0.0, 60.0)  # 0: off; [low inclusive, high]
JOURNAL_MAX_MB = (1.0, 1_000_000.0)  # the journal directory's bound


@dataclass
class Settings:
    mode: str = EMBEDDED
    transport: str = "embedded"  # the embedded backend's transport: embedded (in-process bus) or ros
    rosbridge_url: str = "ws://127.0.0.1:9090"
    tracker_url: str | None = "http://127.0.0.1:8085"
    deploy_mode: str = "native"
    export_dir: Path = Path(".")
    collection_rate: float = 10.0
    max_points: int = 1000
    speed: float = 0.5
    turn: float = 1.0
    repeat_rate: float | None = 10.0  # the ceiling on commands a second (None: none, as in `compare`)
    key_timeout: float = 0.6
    ui_rate: float = 5.0  # redraws per second, however fast data arrives
    # analytics and latency figures (screens 2, 3, the dashboard): once a second, as system monitors
    # refresh (htop 1.5 s, glances 2 s); at 2 Hz the analytics screen cost the console 17 % more CPU
    # (bench/tui.py, session 16, docs/BENCHMARKS.md) and read no better
    analytics_rate: float = 1.0
    poll_period: float = 0.5  # tracker API poll, 2 Hz, while a screen shows the latency figures...
    idle_poll_period: float = 2.0  # ...and every 2 s while none does (the status line's reachability)
    live: bool = True  # timers and workers on; snapshot tests turn it off for still frames
    handle_signals: bool = True
    offset_warn_ms: float = 10.0  # warn when the estimated clock offset to the tracker exceeds this
    config_path: Path | None = None  # where a theme chosen in the palette is kept (None: nowhere)
    theme: str | None = None  # from the config file
    start_paused: bool = False  # analytics recording starts at once unless this is set (``r`` toggles it)
    notes: tuple[str, ...] = ()  # settings the command line asked for and the console changed, said once
    # observe mode: analytics of whatever drives the robot, from its own topics (analytics/observe.py)
    observe: bool = False
    observe_label: str = "observed"  # what drives: the observed samples' algorithm
    robot_name: str = ""  # the robot's name (the fleet's), first in the status line; "" none given
    cmd_topic: str = "cmd_vel"  # relative names resolve under the link's namespace
    cmd_stamped: bool = False  # geometry_msgs/TwistStamped (its age is the sample's latency), else Twist
    plan_topic: str = "plan"
    goal_topic: str = "goal_pose"
    status_topic: str = "navigate_to_pose/_action/status"  # action_msgs/GoalStatusArray: its runs' ends
    namespace: str = ""  # the robot's namespace: relative topic and action names resolve under it
    odom_topic: str = "odom"
    # action servers whose goals a stop cancels (control/stop.py); None: Nav2's in observe mode, else none
    stop_actions: tuple[str, ...] | None = None
    # the session's journal (session/journal.py): its directory (None: no journal, as in tests and
    # `compare`; the command line gives the user data directory unless --no-journal) and its bound
    journal_dir: Path | None = None
    journal_max_mb: float = 256.0
    # a mission holds when the person's terminal has not answered for this long, s (0: never; heartbeat.py)
    operator_timeout: float = 1.0  # ~10 MB an hour at 10 samples/s with the latency and link records
