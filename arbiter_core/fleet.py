"""The fleet's wire schema: what a robot announces on Zenoh and what a console accepts. Pure.

One definition for both sides (``arbiter_backend.fleet`` publishes, ``arbiter_tui.fleet`` reads): the
key expressions, the four payloads and the history answer, their size limits and rates, and the checks.
Every payload is JSON, an object with ``v`` (this schema's version, :data:`VERSION`), ``kind``, ``robot``
(the name its key carries) and ``t`` (the robot's wall clock when it was made, epoch seconds)::

    arbiter/<name>/alive     a liveliness token: present while the robot's session is
    arbiter/<name>/status    every STATUS_PERIOD_S: who drives, mode, controller and progress, pose,
                             velocity, the URLs a console opens
    arbiter/<name>/latency   every LATENCY_PERIOD_S: the tracker's summary and the host's clock sync
    arbiter/<name>/topics    every TOPICS_PERIOD_S: each topic's health, the worst first
    arbiter/<name>/runs      as a run ends (at most one a RUNS_MIN_GAP_S): its grade and the run count
    arbiter/<name>/history   a queryable: the last N minutes of those payloads (``?minutes=N``)
    arbiter/<name>/stop      a queryable: stop whatever drives the robot; the answer says what it did
                             (:class:`StopAnswer`). Who may ask is the router's access control.

A payload is checked by :func:`decode` before anything reads it: its size (before it is decoded), UTF-8,
JSON without NaN or Infinity, the version, the kind, the robot's name against its key (a robot's
payload never shows under another's name), then every field's type and range. Whatever is wrong is one
:class:`FleetPayloadError` line. The publisher encodes with :func:`encode`, which refuses (``ValueError``)
what the reader would refuse, so a robot cannot send what a console drops.

The bound on what a robot sends (payloads only; Zenoh adds its framing and keep-alives) is
:data:`BOUND_BYTES_PER_S`: each kind's size limit over its period.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, Literal, overload

from .topicstats import Expectation, TopicFigures

VERSION = 1
PREFIX = "arbiter"
ALIVE, STATUS, LATENCY, TOPICS, RUNS, HISTORY = "alive", "status", "latency", "topics", "runs", "history"
STOP = "stop"
KINDS = (STATUS, LATENCY, TOPICS, RUNS)  # the published payloads (alive is a token, history, stop queryables)

STATUS_PERIOD_S = 1.0
LATENCY_PERIOD_S = 2.0
TOPICS_PERIOD_S = 5.0
RUNS_MIN_GAP_S = 5.0
PERIOD_S = {STATUS: STATUS_PERIOD_S, LATENCY: LATENCY_PERIOD_S, TOPICS: TOPICS_PERIOD_S, RUNS: RUNS_MIN_GAP_S}
MAX_BYTES = {STATUS: 1536, LATENCY: 768, TOPICS: 4096, RUNS: 1024, HISTORY: 256 * 1024, STOP: 2048}
BOUND_BYTES_PER_S = round(sum(MAX_BYTES[k] / PERIOD_S[k] for k in KINDS))
HISTORY_MINUTES = 10.0  # what a robot keeps for its history queryable (and the most a query may ask)
MAX_TOPICS = 40  # topics in one payload, the worst first (``watched`` says how many there are)

DRIVERS = ("console", "robot", "foreign", "nobody")
DRIVER_WORDS = {
    "console": "console",  # stamped commands arriving from a console over the bridge
    "robot": "robot-side controller",  # arbiter-backend --autonomy runs a mission
    "foreign": "foreign controller",  # commands on the robot's cmd_vel that are none of ours
    "nobody": "nobody",
}
# a topic's health against the robot's expectations, worst first (the topics payload's order)
HEALTH = ("missing", "below", "silent", "slow", "unknown", "waiting", "quiet", "unmeasured", "ok")
OUTCOMES = ("completed", "aborted", "overridden")
PROTOCOLS = ("tcp", "udp", "tls", "quic", "ws", "unixsock-stream")

NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,62}")
_ENDPOINT_RE = re.compile(r"([a-z-]+)/(\S+)")
_STR_MAX = {"name": 63, "short": 40, "detail": 120, "url": 200, "topic": 120}


class FleetPayloadError(ValueError):
    """A payload a console does not accept, in one line (no newline, at most ~200 characters)."""


def robot_name(text: str) -> str:
    """A robot's name as its key carries it: one key-expression chunk of letters, digits, ``_ . -``,
    starting with a letter or digit, at most 63 characters. ValueError in one line otherwise."""
    if not isinstance(text, str) or not NAME_RE.fullmatch(text):
        raise ValueError(
            f"robot name {str(text)[:70]!r} is not one key chunk: use letters, digits, '_', '.', '-' "
            "(starting with a letter or digit, at most 63)"
        )
    return text


def default_name(namespace: str, hostname: str) -> str:
    """The name a backend announces without ``--robot-name``: its namespace (``/site/robot1`` ->
    ``site.robot1``), else this host's name with what a key cannot hold replaced by ``-``."""
    parts = [p for p in namespace.split("/") if p]
    if parts:
        return robot_name(".".join(parts)[:63])
    clean = re.sub(r"[^A-Za-z0-9_.-]", "-", hostname.split(".")[0] or hostname).lstrip("_.-")[:63]
    return clean or "robot"


def key(name: str, kind: str) -> str:
    return f"{PREFIX}/{name}/{kind}"


def parse_key(text: str) -> tuple[str, str] | None:
    """``arbiter/<name>/<kind>`` -> (name, kind); None for any other key (a console ignores it)."""
    parts = text.split("/")
    if len(parts) != 3 or parts[0] != PREFIX or not NAME_RE.fullmatch(parts[1]):
        return None
    return parts[1], parts[2]


def parse_endpoints(text: str) -> tuple[str, ...]:
    """``tcp/10.0.0.5:7447,tls/router.lan:7447`` -> the endpoints; ValueError in one line naming the bad
    one. The address is Zenoh's to resolve; this checks the form and the protocol."""
    out = []
    for item in (p.strip() for p in text.split(",")):
        if not item:
            continue
        m = _ENDPOINT_RE.fullmatch(item)
        if m is None or m.group(1) not in PROTOCOLS:
            raise ValueError(
                f"{item[:80]!r} is not a Zenoh endpoint: write PROTOCOL/ADDRESS with a protocol among "
                f"{', '.join(PROTOCOLS)}, e.g. tcp/192.168.1.10:7447"
            )
        out.append(item)
    if not out:
        raise ValueError("no endpoint given: write PROTOCOL/ADDRESS[,...], e.g. tcp/192.168.1.10:7447")
    return tuple(out)


# -- field checks (raise FleetPayloadError naming the field) ---------------------------------------
# each first takes the common case (the right type, in range) at once: a console checks ~1,000 payloads
# a second at 500 robots; anything else goes the long way, which says what is wrong
_INF = math.inf


def _fail(where: str, what: str, got: Any) -> FleetPayloadError:
    shown = repr(got)
    return FleetPayloadError(f"{where} must be {what}, got {shown[:40]}{'...' if len(shown) > 40 else ''}")


def _get(obj: dict[str, Any], where: str, name: str, optional: bool) -> Any:
    if name not in obj:
        if optional:
            return None
        raise FleetPayloadError(f"{where}.{name} is missing")
    return obj[name]


@overload
def _num(
    obj: dict[str, Any], where: str, name: str, optional: Literal[False] = False, lo: float | None = None
) -> float: ...
@overload
def _num(
    obj: dict[str, Any], where: str, name: str, optional: Literal[True], lo: float | None = None
) -> float | None: ...
def _num(
    obj: dict[str, Any], where: str, name: str, optional: bool = False, lo: float | None = None
) -> float | None:
    v = obj.get(name)
    if type(v) is float and -_INF < v < _INF and (lo is None or v >= lo):  # the common case, at once
        return v
    v = _get(obj, where, name, optional)
    if v is None and optional:
        return None
    ok = isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
    if not ok or (lo is not None and v < lo):
        raise _fail(f"{where}.{name}", "a finite number" + ("" if lo is None else f" >= {lo:g}"), v)
    return float(v)


@overload
def _int(obj: dict[str, Any], where: str, name: str, optional: Literal[False] = False) -> int: ...
@overload
def _int(obj: dict[str, Any], where: str, name: str, optional: Literal[True]) -> int | None: ...
def _int(obj: dict[str, Any], where: str, name: str, optional: bool = False) -> int | None:
    v = obj.get(name)
    if type(v) is int and 0 <= v < 2**53:  # the common case, at once
        return v
    v = _get(obj, where, name, optional)
    if v is None and optional:
        return None
    if not isinstance(v, int) or isinstance(v, bool) or not 0 <= v < 2**53:
        raise _fail(f"{where}.{name}", "a whole number >= 0", v)
    return v


@overload
def _str(
    obj: dict[str, Any],
    where: str,
    name: str,
    size: str,
    optional: Literal[False] = False,
    choices: Sequence[str] | None = None,
) -> str: ...
@overload
def _str(
    obj: dict[str, Any],
    where: str,
    name: str,
    size: str,
    optional: Literal[True],
    choices: Sequence[str] | None = None,
) -> str | None: ...
def _str(
    obj: dict[str, Any],
    where: str,
    name: str,
    size: str,
    optional: bool = False,
    choices: Sequence[str] | None = None,
) -> str | None:
    v = obj.get(name)
    fits = type(v) is str and 0 < len(v) <= _STR_MAX[size] and v.isprintable()
    if fits and (choices is None or v in choices):
        return v  # the common case, at once
    v = _get(obj, where, name, optional)
    if v is None and optional:
        return None
    limit = _STR_MAX[size]
    if not isinstance(v, str) or not v or len(v) > limit or not v.isprintable():
        raise _fail(f"{where}.{name}", f"a printable string of 1 to {limit} characters", v)
    if choices is not None and v not in choices:
        raise _fail(f"{where}.{name}", f"one of {', '.join(choices)}", v)
    return v


def _bool(obj: dict[str, Any], where: str, name: str) -> bool | None:
    v = obj.get(name)
    if v is not None and not isinstance(v, bool):
        raise _fail(f"{where}.{name}", "true, false or null", v)
    return v


@overload
def _vector(obj: dict[str, Any], where: str, name: str, n: Literal[2]) -> tuple[float, float] | None: ...
@overload
def _vector(
    obj: dict[str, Any], where: str, name: str, n: Literal[3]
) -> tuple[float, float, float] | None: ...
def _vector(obj: dict[str, Any], where: str, name: str, n: int) -> tuple[float, ...] | None:
    v = obj.get(name)
    if v is None:
        return None
    if type(v) is list and len(v) == n and all(type(x) is float and -_INF < x < _INF for x in v):
        return tuple(v)  # the common case, at once
    if not isinstance(v, list) or len(v) != n:
        raise _fail(f"{where}.{name}", f"null or a list of {n} finite numbers", v)
    return tuple(_num({f"{name}[{i}]": x}, where, f"{name}[{i}]") for i, x in enumerate(v))


def _url(obj: dict[str, Any], where: str, name: str, schemes: tuple[str, ...]) -> str | None:
    v = _str(obj, where, name, "url", optional=True)
    if v is not None and not v.startswith(tuple(f"{s}://" for s in schemes)):
        raise _fail(f"{where}.{name}", f"null or a {' or '.join(s + '://' for s in schemes)} URL", v)
    return v


def _namespace(obj: dict[str, Any], where: str) -> str | None:
    v = _str(obj, where, "namespace", "topic", optional=True)
    if v is not None and not re.fullmatch(r"(/[A-Za-z_][A-Za-z0-9_]*)+", v):
        raise _fail(f"{where}.namespace", "null or a ROS namespace such as /robot1", v)
    return v


# -- the payloads ----------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class Status:
    """Who drives, what the robot does and where it is; the URLs a console opens it with.

    ``driver``: ``console`` (a console's stamped commands reached the tracker in the last second and no
    robot-side run is in progress), ``robot`` (``arbiter-backend --autonomy`` runs a mission),
    ``foreign`` (messages on the robot's ``cmd_vel`` in the last second that are neither: another
    controller, e.g. Nav2), ``nobody``. ``controller``/``mission``/``run_state``/``waypoint``: the
    robot-side run's (a console's own controller runs on the console: the robot cannot know it, so they
    are null while a console drives). ``pose`` ``[x, y, yaw]`` and ``velocity`` ``[v, w]`` from the
    robot's odometry, null where the backend does not read it."""

    robot: str
    t: float
    started: float
    driver: str
    mode: str
    auth: str = "none"  # "token": the robot's servers want its token (a console needs --token-file)
    driver_detail: str | None = None
    controller: str | None = None
    mission: str | None = None
    run_state: str | None = None
    waypoint: int | None = None
    waypoints: int | None = None
    pose: tuple[float, float, float] | None = None
    velocity: tuple[float, float] | None = None
    rosbridge: str | None = None
    tracker: str | None = None
    namespace: str | None = None  # the robot's ROS namespace (a console opens it with --namespace)
    runs: int = 0  # runs ended since the backend started
    lease_ms: int | None = None  # the liveliness lease the robot announces (how soon it reads "lost")

    kind = STATUS

    @classmethod
    def from_obj(cls, o: dict[str, Any]) -> Status:
        w = STATUS
        return cls(
            robot=o["robot"],
            t=_num(o, w, "t", lo=0),
            started=_num(o, w, "started", lo=0),
            driver=_str(o, w, "driver", "short", choices=DRIVERS),
            mode=_str(o, w, "mode", "short"),
            auth=_str(o, w, "auth", "short", choices=("none", "token")),
            driver_detail=_str(o, w, "driver_detail", "detail", optional=True),
            controller=_str(o, w, "controller", "short", optional=True),
            mission=_str(o, w, "mission", "short", optional=True),
            run_state=_str(o, w, "run_state", "short", optional=True),
            waypoint=_int(o, w, "waypoint", optional=True),
            waypoints=_int(o, w, "waypoints", optional=True),
            pose=_vector(o, w, "pose", 3),
            velocity=_vector(o, w, "velocity", 2),
            rosbridge=_url(o, w, "rosbridge", ("ws", "wss")),
            tracker=_url(o, w, "tracker", ("http", "https")),
            namespace=_namespace(o, w),
            runs=_int(o, w, "runs"),
            lease_ms=_int(o, w, "lease_ms", optional=True),
        )


@dataclass(frozen=True, slots=True)
class Latency:
    """The tracker's summary over its window of records (command latency one way, console to robot),
    and this host's clock synchronisation (``sync_error_ms``: the host clock is within this of true time,
    as chrony/timesyncd/adjtimex say; with the console host's own it bounds the two clocks' offset).
    ``stale`` and ``rejected``: commands the robot dropped as too old or malformed (commands lost on
    the way never reach the robot: the console counts those)."""

    robot: str
    t: float
    count: int = 0  # records in the tracker's window
    total: int = 0  # commands received since the backend started
    p50_ms: float | None = None
    p95_ms: float | None = None
    max_ms: float | None = None
    stale: int = 0
    rejected: int = 0
    sync_source: str = "unknown"
    sync_ok: bool | None = None  # None: cannot tell
    sync_error_ms: float | None = None

    kind = LATENCY

    @classmethod
    def from_obj(cls, o: dict[str, Any]) -> Latency:
        w = LATENCY
        return cls(
            robot=o["robot"],
            t=_num(o, w, "t", lo=0),
            count=_int(o, w, "count"),
            total=_int(o, w, "total"),
            p50_ms=_num(o, w, "p50_ms", optional=True),
            p95_ms=_num(o, w, "p95_ms", optional=True),
            max_ms=_num(o, w, "max_ms", optional=True),
            stale=_int(o, w, "stale"),
            rejected=_int(o, w, "rejected"),
            sync_source=_str(o, w, "sync_source", "short"),
            sync_ok=_bool(o, w, "sync_ok"),
            sync_error_ms=_num(o, w, "sync_error_ms", optional=True, lo=0),
        )


@dataclass(frozen=True, slots=True)
class TopicHealth:
    name: str
    health: str  # one of HEALTH
    hz: float | None = None
    age_ms: float | None = None
    expect_hz: float | None = None  # the robot's expectation (``arbiter-backend --expect``), if any

    def words(self) -> str:
        """``/scan silent`` / ``/odom 31.2<45 Hz`` / ``/map missing``."""
        if self.health == "below" and self.expect_hz is not None:
            have = "no messages" if self.hz is None else f"{self.hz:.3g}"
            return f"{self.name} {have}<{self.expect_hz:g} Hz"
        return f"{self.name} {self.health}"


@dataclass(frozen=True, slots=True)
class Topics:
    """Every watched topic's health, the worst first (:data:`HEALTH` order), at most
    :data:`MAX_TOPICS`; ``watched`` counts them all."""

    robot: str
    t: float
    window_s: float
    watched: int
    topics: tuple[TopicHealth, ...] = ()
    # why the topics' health is ``unknown`` ("monitor restarted: …", ``TopicsAnswer.interrupted``)
    monitor: str | None = None

    kind = TOPICS

    @property
    def worst(self) -> TopicHealth | None:
        return self.topics[0] if self.topics else None

    @classmethod
    def from_obj(cls, o: dict[str, Any]) -> Topics:
        w = TOPICS
        raw = o.get("topics")
        if not isinstance(raw, list) or len(raw) > MAX_TOPICS:
            raise _fail(f"{w}.topics", f"a list of at most {MAX_TOPICS} topics", raw)
        items = []
        for i, t in enumerate(raw):
            where = f"{w}.topics[{i}]"
            if not isinstance(t, dict):
                raise _fail(where, "an object", t)
            items.append(
                TopicHealth(
                    name=_str(t, where, "name", "topic"),
                    health=_str(t, where, "health", "short", choices=HEALTH),
                    hz=_num(t, where, "hz", optional=True, lo=0),
                    age_ms=_num(t, where, "age_ms", optional=True, lo=0),
                    expect_hz=_num(t, where, "expect_hz", optional=True, lo=0),
                )
            )
        ranks = [HEALTH.index(t.health) for t in items]
        if ranks != sorted(ranks):
            raise FleetPayloadError(f"{w}.topics must be sorted worst first ({', '.join(HEALTH)})")
        return cls(
            robot=o["robot"],
            t=_num(o, w, "t", lo=0),
            window_s=_num(o, w, "window_s", lo=0),
            watched=_int(o, w, "watched"),
            topics=tuple(items),
            monitor=_str(o, w, "monitor", "detail", optional=True),
        )


@dataclass(frozen=True, slots=True)
class RunGrade:
    """One robot-side run as it ended: its outcome, time, how far it got and how far from its goal it
    stopped. (The console's own runs are graded by the console; the robot cannot see them.)"""

    n: int  # the run's number since the backend started
    controller: str
    mission: str
    outcome: str  # one of OUTCOMES
    time_s: float
    reached: int
    waypoints: int
    final_error_m: float | None = None
    ended: float = 0.0  # epoch s

    def words(self) -> str:
        """``completed 41.2 s, 0.08 m`` / ``aborted 3/4 12.0 s``."""
        err = "" if self.final_error_m is None else f", {self.final_error_m:.2f} m"
        part = "" if self.outcome == "completed" else f" {self.reached}/{self.waypoints}"
        return f"{self.outcome}{part} {self.time_s:.1f} s{err}"


@dataclass(frozen=True, slots=True)
class Runs:
    robot: str
    t: float
    count: int  # runs ended since the backend started
    last: RunGrade

    kind = RUNS

    @classmethod
    def from_obj(cls, o: dict[str, Any]) -> Runs:
        w = RUNS
        r = o.get("last")
        if not isinstance(r, dict):
            raise _fail(f"{w}.last", "an object", r)
        where = f"{w}.last"
        return cls(
            robot=o["robot"],
            t=_num(o, w, "t", lo=0),
            count=_int(o, w, "count"),
            last=RunGrade(
                n=_int(r, where, "n"),
                controller=_str(r, where, "controller", "short"),
                mission=_str(r, where, "mission", "short"),
                outcome=_str(r, where, "outcome", "short", choices=OUTCOMES),
                time_s=_num(r, where, "time_s", lo=0),
                reached=_int(r, where, "reached"),
                waypoints=_int(r, where, "waypoints"),
                final_error_m=_num(r, where, "final_error_m", optional=True, lo=0),
                ended=_num(r, where, "ended", lo=0),
            ),
        )


Payload = Status | Latency | Topics | Runs
_CLASSES: dict[str, type[Payload]] = {STATUS: Status, LATENCY: Latency, TOPICS: Topics, RUNS: Runs}


@dataclass(frozen=True, slots=True)
class History:
    """The answer of ``arbiter/<name>/history``: the robot's payloads of the last ``minutes``, oldest
    first (status thinned to one a HISTORY_STATUS_S, topics to one a HISTORY_TOPICS_S)."""

    robot: str
    t: float
    minutes: float
    entries: tuple[Payload, ...] = field(default_factory=tuple)

    kind = HISTORY


HISTORY_STATUS_S = 10.0
HISTORY_TOPICS_S = 30.0

# -- the stop ---------------------------------------------------------------------------------------
STOP_TIMEOUT_S = 1.0  # a robot that has not answered a stop by then: the console says so
# the robot answers by then, whatever is still under way (a cancel not answered yet is "pending" and
# goes on): half the console's wait, so the answer arrives within it over a slow link
STOP_ANSWER_S = STOP_TIMEOUT_S / 2
# arbiter_core.stopping.Cancel's values
CANCEL_OUTCOMES = ("cancelled", "no goal", "no server", "failed", "pending")


@dataclass(frozen=True, slots=True)
class StopCancel:
    """One action whose goals the robot asked to cancel (``arbiter_core.stopping``)."""

    action: str
    outcome: str  # one of CANCEL_OUTCOMES
    goals: int = 0


@dataclass(frozen=True, slots=True)
class StopAnswer:
    """What a robot did when a fleet console asked it to stop (its answer on ``arbiter/<name>/stop``).

    ``driver``: who drove when the stop came (:data:`DRIVERS`). ``aborted``: the robot-side run it ended
    (``stanley on square at 2/4``), None when none ran. ``zero``: a zero command went out on the robot's
    command output. ``cancels``: the foreign actions whose goals it asked to cancel (only the servers
    there are asked). ``still``: what may drive it on regardless (a console still sending commands), or
    None. ``commands``: the commands its robot-side run had sent when it was aborted."""

    robot: str
    t: float
    driver: str
    zero: bool
    aborted: str | None = None
    commands: int | None = None
    cancels: tuple[StopCancel, ...] = ()
    still: str | None = None

    kind = STOP

    @property
    def sure(self) -> bool:
        """Stopped for sure: nothing still drives it and no cancel failed or is still pending."""
        return self.still is None and all(c.outcome not in ("failed", "pending") for c in self.cancels)

    def words(self) -> str:
        """``stopped: stanley aborted, 0 commands`` / ``stopped: 1 goal of /navigate_to_pose cancelled,
        zero sent`` / ``stopped: nothing was driving, zero sent``; then what still drives it."""
        parts = []
        if self.aborted is not None:
            algo = self.aborted.split(" ", 1)[0]
            sent = self.commands
            n = "" if sent is None else f", {sent} command{'s' if sent != 1 else ''}"
            parts.append(f"{algo} aborted{n}")
        for c in self.cancels:
            if c.outcome == "cancelled":
                parts.append(f"{c.goals} goal{'s' if c.goals != 1 else ''} of {c.action} cancelled")
            elif c.outcome == "failed":
                parts.append(f"{c.action} not cancelled")
            elif c.outcome == "pending":
                parts.append(f"{c.action} cancel pending")
        if not parts and self.still is None:
            parts.append("nothing was driving" if self.driver == "nobody" else f"{self.driver} was driving")
        if self.zero:
            parts.append("zero sent")
        if not parts:
            parts.append("nothing done")
        head = "stopped" if self.sure else "asked"
        return f"{head}: {', '.join(parts)}" + ("" if self.still is None else f"; still: {self.still}")

    @classmethod
    def from_obj(cls, o: dict[str, Any]) -> StopAnswer:
        w = STOP
        raw = o.get("cancels")
        if not isinstance(raw, list) or len(raw) > 16:
            raise _fail(f"{w}.cancels", "a list of at most 16 actions", raw)
        cancels = []
        for i, c in enumerate(raw):
            where = f"{w}.cancels[{i}]"
            if not isinstance(c, dict):
                raise _fail(where, "an object", c)
            cancels.append(
                StopCancel(
                    action=_str(c, where, "action", "topic"),
                    outcome=_str(c, where, "outcome", "short", choices=CANCEL_OUTCOMES),
                    goals=_int(c, where, "goals"),
                )
            )
        zero = o.get("zero")
        if not isinstance(zero, bool):
            raise _fail(f"{w}.zero", "true or false", zero)
        return cls(
            robot=o["robot"],
            t=_num(o, w, "t", lo=0),
            driver=_str(o, w, "driver", "short", choices=DRIVERS),
            zero=zero,
            aborted=_str(o, w, "aborted", "detail", optional=True),
            commands=_int(o, w, "commands", optional=True),
            cancels=tuple(cancels),
            still=_str(o, w, "still", "detail", optional=True),
        )


def to_obj(p: Payload | History | StopAnswer) -> dict[str, Any]:
    """The payload as the JSON object sent (tuples as lists, the header first)."""
    body = asdict(p)
    body.pop("robot")
    if isinstance(p, History):
        body["entries"] = [to_obj(e) for e in p.entries]
    return {"v": VERSION, "kind": p.kind, "robot": p.robot, **body}


def encode(p: Payload | History | StopAnswer) -> bytes:
    """The bytes to publish; ValueError when the reader would refuse them (too big, not finite)."""
    data = json.dumps(to_obj(p), allow_nan=False, separators=(",", ":")).encode()
    if len(data) > MAX_BYTES[p.kind]:
        raise ValueError(f"{p.kind} payload of {len(data)} bytes is over its {MAX_BYTES[p.kind]}-byte limit")
    decode(data, p.kind, p.robot)  # what a console would say of it
    return data


def _no_constant(token: str) -> Any:
    raise FleetPayloadError(f"not JSON a robot may send: {token} (numbers must be finite)")


# one decoder for every payload: json.loads with an argument builds a new decoder (and its scanner) each
# call, a fifth of a console's cost per payload at 500 robots
_DECODER = json.JSONDecoder(parse_constant=_no_constant)


def size_words(n: int) -> str:
    return f"{n / 1e6:.1f} MB" if n >= 1e6 else f"{n / 1e3:.1f} kB" if n >= 1e3 else f"{n} bytes"


def decode(data: bytes, kind: str, robot: str) -> Payload | History | StopAnswer:
    """Check and parse what arrived on ``arbiter/<robot>/<kind>`` (module doc); FleetPayloadError in one
    line naming what is wrong."""
    if kind not in MAX_BYTES:
        raise FleetPayloadError(f"unknown key arbiter/{robot}/{kind[:40]}")
    if len(data) > MAX_BYTES[kind]:
        raise FleetPayloadError(
            f"{kind}: {size_words(len(data))}, over the {size_words(MAX_BYTES[kind])} a {kind} may be"
        )
    try:
        obj = _DECODER.decode(data.decode("utf-8"))
    except FleetPayloadError as exc:
        raise FleetPayloadError(f"{kind}: {exc}") from None
    except UnicodeDecodeError:
        raise FleetPayloadError(f"{kind}: not UTF-8 text ({size_words(len(data))})") from None
    except (ValueError, RecursionError) as exc:
        raise FleetPayloadError(f"{kind}: not JSON ({str(exc).splitlines()[0][:60]})") from None
    return decode_obj(obj, kind, robot)


def decode_obj(obj: Any, kind: str, robot: str) -> Payload | History | StopAnswer:
    checked = _header(obj, kind, robot)
    if kind == HISTORY:
        return _history(checked, robot)
    if kind == STOP:
        return StopAnswer.from_obj(checked)
    return _CLASSES[kind].from_obj(checked)


def _header(obj: Any, kind: str, robot: str) -> dict[str, Any]:
    """``obj`` itself once its type, version, kind and robot are checked."""
    if not isinstance(obj, dict):
        raise FleetPayloadError(f"{kind}: a JSON {type(obj).__name__}, not an object")
    v = obj.get("v")
    if v != VERSION or isinstance(v, bool):
        raise FleetPayloadError(f"{kind}: schema version {str(v)[:12]}, this console reads version {VERSION}")
    if obj.get("kind") != kind:
        raise FleetPayloadError(
            f"{kind}: the payload says kind {str(obj.get('kind'))[:20]!r}, its key {kind}"
        )
    if obj.get("robot") != robot:
        raise FleetPayloadError(
            f"{kind}: the payload names robot {str(obj.get('robot'))[:40]!r} on {robot}'s key"
        )
    return obj


def _history(o: dict[str, Any], robot: str) -> History:
    raw = o.get("entries")
    if not isinstance(raw, list):
        raise _fail("history.entries", "a list", raw)
    entries: list[Payload] = []
    for i, e in enumerate(raw):
        k = e.get("kind") if isinstance(e, dict) else None
        if k not in KINDS:
            raise _fail(f"history.entries[{i}].kind", f"one of {', '.join(KINDS)}", k)
        try:
            entries.append(_CLASSES[k].from_obj(_header(e, k, robot)))  # decode_obj, k not HISTORY
        except FleetPayloadError as exc:
            raise FleetPayloadError(f"history.entries[{i}]: {exc}") from None
    return History(
        robot=robot,
        t=_num(o, HISTORY, "t", lo=0),
        minutes=_num(o, HISTORY, "minutes", lo=0),
        entries=tuple(entries),
    )


def history_minutes(parameters: str) -> float:
    """The ``minutes=N`` of a history query's parameters (default and ceiling HISTORY_MINUTES)."""
    for part in parameters.split(";"):
        name, _, value = part.partition("=")
        if name.strip() == "minutes":
            try:
                m = float(value)
            except ValueError:
                return HISTORY_MINUTES
            return min(max(m, 0.0), HISTORY_MINUTES) if math.isfinite(m) else HISTORY_MINUTES
    return HISTORY_MINUTES


# -- building the topics payload (the publisher's side, pure) --------------------------------------
def health_of(fig: TopicFigures, expect_hz: float | None) -> str:
    """One topic's health: ``below`` its expectation, else its monitor state (``topicstats``); while the
    monitor is down (``unknown``) nothing is known of it, its expectation included."""
    if fig.state in ("unmeasured", "unknown"):
        return fig.state
    if expect_hz is not None and (fig.rate_hz is None or fig.rate_hz < expect_hz):
        return "below"
    return fig.state if fig.state in HEALTH else "ok"


def topics_payload(
    robot: str,
    t: float,
    window_s: float,
    figures: Sequence[TopicFigures],
    expect: Sequence[Expectation],
    monitor: str | None = None,
) -> Topics:
    """Every topic's health against ``expect`` (an expected topic absent is ``missing``), the worst
    first, as many as fit in the payload's limit (``watched`` counts them all); ``monitor``: why the
    healths are ``unknown`` (``TopicWatch.interrupted``)."""
    note = None if monitor is None else "".join(c if c.isprintable() else " " for c in monitor)
    note = note[: _STR_MAX["detail"]] if note else None
    wanted = {e.topic: e.min_hz for e in expect}
    items = [
        TopicHealth(f.name[: _STR_MAX["topic"]], health_of(f, wanted.get(f.name)), _round(f.rate_hz),
                    _round(f.age_ms), wanted.get(f.name))
        for f in figures
    ]  # fmt: skip
    seen = {f.name for f in figures}
    items += [TopicHealth(name[: _STR_MAX["topic"]], "missing", None, None, hz) for name, hz in wanted.items()
              if name not in seen]  # fmt: skip
    items.sort(key=lambda h: (HEALTH.index(h.health), h.name))
    watched = len(items)
    items = items[:MAX_TOPICS]
    while True:
        p = Topics(robot, t, window_s, watched, tuple(items), note)
        if len(json.dumps(to_obj(p), separators=(",", ":"))) <= MAX_BYTES[TOPICS] or not items:
            return p
        items = items[: len(items) * 3 // 4]


def _round(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(v) else round(v, 2)


# -- a Zenoh session's settings (both sides insert these into a zenoh.Config) -----------------------
# how to add the [fleet] extra to each install (docs/INSTALL.md): the robot's is built from a clone
FLEET_INSTALLS = {
    "arbiter-tui": "pip install 'arbiter-tui[fleet]'",
    "arbiter-backend": "pip install './robot[fleet]' (the robot's install, from the repository's clone)",
}


def zenoh_missing(distribution: str | None = "arbiter-tui") -> str:
    """The one line saying how to get Zenoh into the install ``distribution`` (None: not installed,
    a source tree: the console's)."""
    how = FLEET_INSTALLS.get(distribution or "arbiter-tui", FLEET_INSTALLS["arbiter-tui"])
    return f"needs eclipse-zenoh (the [fleet] extra): {how}"


ZENOH_MISSING = zenoh_missing()
DEFAULT_LEASE_MS = 1500  # a robot whose session goes silent this long is dropped by its router: "lost"
MAX_MESSAGE_BYTES = 16 * 1024 * 1024  # larger messages are dropped by Zenoh's transport, unread


def session_settings(
    mode: str,
    connect: Sequence[str] = (),
    listen: Sequence[str] = (),
    lease_ms: int | None = None,
    own_file: bool = False,
) -> dict[str, Any]:
    """The keys (Zenoh config paths) and values our flags set in a session's config, over the user's
    config file if any. ``connect``: retried for ever (a robot or a console started before its router
    waits for it); ``lease_ms``: the link lease this node announces, so its router drops it that long
    after it goes silent (Zenoh sends keep-alives four times a lease). Without a config file of the
    user's (``own_file``), multicast scouting is off: only the endpoints given are used."""
    out: dict[str, Any] = {"mode": mode, "transport/link/rx/max_message_size": MAX_MESSAGE_BYTES}
    if connect:
        out["connect/endpoints"] = list(connect)
        out["connect/timeout_ms"] = -1
    if listen:
        out["listen/endpoints"] = list(listen)
    elif mode == "peer" and not own_file:
        out["listen/endpoints"] = []  # a peer listens on every interface by default: a robot need not
    if lease_ms is not None:
        out["transport/link/tx/lease"] = lease_ms
    if not own_file:
        out["scouting/multicast/enabled"] = False
        out["scouting/gossip/enabled"] = mode == "router"
    return out
