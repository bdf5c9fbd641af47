"""The fleet's rows: what the console knows of each robot, and the frozen view the screen and ``--json``
show. Pure: no Zenoh, no Textual, no clock (wall and monotonic seconds are passed in).

A robot is listed from the first thing heard of it (its liveliness token or a payload) and never dropped:

- ``alive``: its token is present and its last valid ``status`` is at most ``stale_after`` old;
- ``stale``: its token is present but no valid status for ``stale_after`` (or none yet), or payloads
  arrive without a token (an ACL or a robot that does not announce one);
- ``lost``: its token went away (its session closed, or its router dropped it after its lease): "lost
  since 14:02:11", until the token comes back.
- ``unknown``: this console's own link to its router is down (``link``): nobody can tell, "unknown since
  14:02:11", until the link is back and the tokens have had ``LINK_SETTLE_S`` to come back with it; or
  every robot (two or more) went silent at once for ``SILENT_S`` with its token still there (a frozen
  router keeps its links open until its lease): unknown since the last payload heard.

A payload that fails ``arbiter_core.fleet.decode`` marks its robot's row with the reason for
``BAD_HOLD_S`` after the last such payload (the count stays); the row's other figures are the last good
ones. Severity orders the rows: lost, bad data, stale, a warning (a topic missing, below its
expectation, silent or slow), ok; then by name.
"""

from __future__ import annotations

import fnmatch
import time
from dataclasses import dataclass, field, fields
from typing import Any

from arbiter_core import fleet
from arbiter_core.fleet import Latency, Runs, Status, Topics
from arbiter_core.timesync import TimeSync, one_way_bound_ms

from .flood import Meter

STALE_AFTER_S = 5.0  # five status periods without one: stale
BAD_HOLD_S = 60.0  # a row says "bad data" this long after the last bad payload
MAX_ROBOTS = 1000  # names beyond are counted, not listed (a flood of names cannot exhaust the console)
STATES = ("alive", "stale", "lost", "unknown")
LINK_GRACE_S = 1.0  # tokens that went this long before the console's link went down went with it
LINK_SETTLE_S = 1.0  # the link back: the tokens there come back within this (the router sends them)
SILENT_S = 3.0  # no payload from any of two or more robots this long: the link is silent, not the robots
SILENT_MIN_ROBOTS = 2
LOST, BAD, STALE, WARN, OK = 4, 3, 2, 1, 0
WARN_HEALTH = ("missing", "below", "silent", "slow", "unknown")


@dataclass
class _Robot:
    """Everything heard of one robot (mutable; only the model touches it)."""

    name: str
    token: bool = False
    alive_since: float | None = None  # wall s: the token appeared
    token_mono: float | None = None
    lost_at: float | None = None  # wall s: the token went away
    status: Status | None = None
    status_mono: float | None = None
    latency: Latency | None = None
    topics: Topics | None = None
    runs: Runs | None = None
    last_mono: float | None = None  # the last valid payload of any kind
    bad: str | None = None
    bad_mono: float | None = None
    bad_count: int = 0
    received: int = 0  # valid payloads
    received_bytes: int = 0
    meter: Meter = field(default_factory=Meter)  # payloads over its kinds' rates (flood.py)


@dataclass(frozen=True, slots=True)
class Row:
    """One robot as the screen and ``--json`` show it (times: wall epoch seconds)."""

    name: str
    state: str  # alive | stale | lost
    severity: int
    since: float | None = None  # lost: when; alive/stale: when its token appeared
    age_s: float | None = None  # since its last valid payload (None: none yet)
    driver: str | None = None
    driver_detail: str | None = None
    mode: str | None = None
    p50_ms: float | None = None
    p95_ms: float | None = None
    latency_count: int | None = None
    offset_bound_ms: float | None = None  # the two hosts' clocks are within this of each other
    clock_note: str | None = None  # why there is no bound
    worst_topic: str | None = None
    worst_health: str | None = None
    controller: str | None = None
    progress: str | None = None  # "2/4 running"
    grade: str | None = None  # the last robot-side run's
    runs: int | None = None
    bad: str | None = None
    bad_count: int = 0
    note: str | None = None
    rosbridge: str | None = None
    tracker: str | None = None
    namespace: str | None = None
    auth: str | None = None
    pose: tuple[float, ...] | None = None
    velocity: tuple[float, ...] | None = None
    figures_at: float | None = None  # lost: the wall time its figures date from (its last payload)
    flooding: float | None = None  # payloads a second it sends over its kinds' rates (the excess dropped)

    def to_json(self) -> dict[str, Any]:
        out = {f.name: _plain(getattr(self, f.name)) for f in fields(self)}
        out["cells"] = dict(zip(COLUMNS, cells(self), strict=True))
        return out


def _worst_words(top: Topics | None) -> str | None:
    """The worst topic's words; while the robot's topic monitor restarts, that ("monitor restarted: …"),
    not each topic's ``unknown``."""
    if top is None:
        return None
    if top.monitor:
        return top.monitor
    return None if top.worst is None else top.worst.words()


def _grade(last: fleet.RunGrade, current: str | None) -> str:
    """The last run's grade, naming its controller when another one is current."""
    return last.words() if current in (None, last.controller) else f"{last.controller}: {last.words()}"


def _plain(v: Any) -> Any:
    return list(v) if isinstance(v, tuple) else round(v, 3) if isinstance(v, float) else v


@dataclass(frozen=True, slots=True)
class FleetView:
    """What the screen shows at one moment: the rows that pass the filter, in severity order, and the
    counts over every robot."""

    rows: tuple[Row, ...] = ()
    counts: tuple[tuple[str, int], ...] = ()  # (state or "bad", n) over all robots
    total: int = 0
    filter: str = ""
    ignored: int = 0  # names beyond MAX_ROBOTS
    unknown: int = 0  # samples on keys that are not a robot's payload (dropped)
    flood_dropped: int = 0  # payloads dropped as over their robot's rate
    now: float = 0.0  # wall s the view was made at (the screen's "lost since" ages)
    session: str = ""  # where the console's Zenoh session is ("router on tcp/...", "connecting to ...")
    error: str | None = None
    # the robots in trouble over all robots (not only those the filter shows), by name: lost, bad, stale
    problems: tuple[tuple[str, tuple[str, ...]], ...] = ()
    silent: float | None = None  # wall s since which no robot was heard (FleetModel.silent_since)

    def names(self, what: str) -> tuple[str, ...]:
        """The robots ``lost``, with ``bad`` data, ``stale`` or ``unknown`` (over all robots)."""
        return dict(self.problems).get(what, ())

    def to_json(self) -> dict[str, Any]:
        return {
            "t": round(self.now, 3),
            "session": self.session,
            "error": self.error,
            "filter": self.filter,
            "counts": dict(self.counts),
            "total": self.total,
            "ignored": self.ignored,
            "dropped": {"odd_keys": self.unknown, "over_rate": self.flood_dropped},
            "problems": {what: list(names) for what, names in self.problems},
            "robots": [r.to_json() for r in self.rows],
        }


def matches(name: str, pattern: str) -> bool:
    """A name glob (``robot-*``, ``lab?.*``); text without ``* ? [`` matches anywhere in the name."""
    if not pattern:
        return True
    if not any(c in pattern for c in "*?["):
        return pattern.lower() in name.lower()
    return fnmatch.fnmatchcase(name, pattern)


@dataclass
class FleetModel:
    stale_after: float = STALE_AFTER_S
    console_sync: TimeSync | None = None
    _robots: dict[str, _Robot] = field(default_factory=dict)
    ignored: set[str] = field(default_factory=set)
    unknown: int = 0
    flood_dropped: int = 0  # payloads dropped as over their robot's rate
    link_down: tuple[float, float] | None = None  # (wall, mono) this console's link to its router went down
    link_back: float | None = None  # mono s it came back (None: down now, or never down)

    def link(self, up: bool, wall: float, mono: float) -> None:
        """This console's own link to its router (a client's; a router's own console has none) went down
        or came back."""
        if not up and (self.link_down is None or self.link_back is not None):
            self.link_down, self.link_back = (wall, mono), None
        elif up and self.link_down is not None and self.link_back is None:
            self.link_back = mono

    def silent_since(self, wall: float, mono: float) -> float | None:
        """Since when (wall) no robot has been heard, when two or more with a token have been silent for
        SILENT_S at once: the router (or this console's network) is silent, not the robots."""
        heard = [r.last_mono for r in self._robots.values() if r.token and r.last_mono is not None]
        if len(heard) < SILENT_MIN_ROBOTS or mono - max(heard) < SILENT_S:
            return None
        return wall - (mono - max(heard))

    def _unknown(self, r: _Robot, mono: float, silent: float | None = None) -> float | None:
        """Since when (wall) nobody can tell ``r``'s state because this console's link was down."""
        if silent is not None and r.token:
            return silent
        if self.link_down is None:
            return None
        down_wall, _ = self.link_down
        if self.link_back is None:
            return down_wall  # down now: no robot is lost or alive
        went_with_it = not r.token and r.lost_at is not None and r.lost_at >= down_wall - LINK_GRACE_S
        return down_wall if went_with_it and mono - self.link_back < LINK_SETTLE_S else None

    def _robot(self, name: str) -> _Robot | None:
        r = self._robots.get(name)
        if r is None:
            if len(self._robots) >= MAX_ROBOTS:
                if len(self.ignored) < MAX_ROBOTS:
                    self.ignored.add(name)
                return None
            r = self._robots[name] = _Robot(name)
        return r

    # -- what arrives -------------------------------------------------------------------------------
    def token(self, name: str, present: bool, wall: float, mono: float) -> None:
        r = self._robot(name)
        if r is None:
            return
        if present and not r.token:
            r.token, r.alive_since, r.token_mono, r.lost_at = True, wall, mono, None
        elif not present and r.token:
            r.token, r.lost_at = False, wall

    def accept(self, payload: fleet.Payload, size: int, mono: float) -> None:
        """A payload that passed ``fleet.decode`` on its robot's key."""
        r = self._robot(payload.robot)
        if r is None:
            return
        if isinstance(payload, Latency | Topics | Runs):
            held = getattr(r, payload.kind)
            if held is not None and held.t > payload.t:
                return  # an older one (from the history) than the one held
        r.last_mono = mono
        r.received += 1
        r.received_bytes += size
        if isinstance(payload, Status):
            r.status, r.status_mono = payload, mono
        elif isinstance(payload, Latency):
            r.latency = payload
        elif isinstance(payload, Topics):
            r.topics = payload
        elif isinstance(payload, Runs):
            r.runs = payload

    def reject(self, name: str, reason: str, mono: float) -> None:
        """A payload on ``name``'s key that did not pass: the row says so."""
        r = self._robot(name)
        if r is None:
            return
        r.bad, r.bad_mono = reason[:200], mono
        r.bad_count += 1

    def backfill(self, answer: fleet.History, mono: float) -> None:
        """A robot's history answer, asked when it first appears: the newest latency, topics and runs
        in it, unless newer ones arrived meanwhile (its status is never taken from the past: a row's
        freshness is its live status)."""
        newest: dict[str, fleet.Payload] = {}
        for e in answer.entries:
            if not isinstance(e, Status):
                newest[e.kind] = e
        for p in newest.values():
            self.accept(p, 0, mono)

    def unknown_key(self) -> None:
        self.unknown += 1

    def admit(self, name: str, kind: str, mono: float) -> bool:
        """A payload of ``kind`` on ``name``'s key, before it is copied or parsed: False when it is over
        its kind's rate (dropped, counted; the row says the robot floods)."""
        r = self._robot(name)
        if r is None:
            return False
        if r.meter.admit(kind, mono):
            return True
        self.flood_dropped += 1
        return False

    # -- what is shown ------------------------------------------------------------------------------
    def names(self) -> list[str]:
        return sorted(self._robots)

    def received_bytes(self) -> dict[str, int]:
        return {n: r.received_bytes for n, r in self._robots.items()}

    def row(self, r: _Robot, wall: float, mono: float, silent: float | None = None) -> Row:
        note = None
        unknown = self._unknown(r, mono, silent)
        if unknown is not None:
            state, since = "unknown", unknown
        elif not r.token and r.lost_at is not None:
            state, since = "lost", r.lost_at
        elif not r.token:
            state, since, note = "stale", None, "no liveliness token (payloads only)"
        else:
            since = r.alive_since
            fresh = r.status_mono is not None and mono - r.status_mono <= self.stale_after
            # its token (re)appeared and no status since: alive while it may still be starting
            waiting = r.status_mono is None or (r.token_mono is not None and r.status_mono < r.token_mono)
            waited = r.token_mono is not None and mono - r.token_mono > self.stale_after
            state = "alive" if fresh or (waiting and not waited) else "stale"
            if r.status_mono is None:
                note = "no status yet"
        bad = r.bad if r.bad_mono is not None and mono - r.bad_mono <= BAD_HOLD_S else None
        flooding = r.meter.flooding(mono)
        s, lat, top, runs = r.status, r.latency, r.topics, r.runs
        worst = top.worst if top is not None else None
        bound, clock_note = self._clock(lat)
        gone = state in ("lost", "unknown")  # its figures are its last ones
        if state == "lost":
            severity = LOST
        elif bad is not None or flooding is not None:
            severity = BAD
        elif gone or state == "stale":
            severity = STALE
        elif worst is not None and worst.health in WARN_HEALTH:
            severity = WARN
        else:
            severity = OK
        progress = None
        if s is not None and s.run_state is not None and s.waypoints:
            was = "was " if gone else ""  # a lost robot's run is not known to run on
            progress = f"{s.waypoint}/{s.waypoints} {was}{s.run_state}"
        controller = s.controller if s is not None and s.controller else None
        if controller is None and runs is not None:
            controller = runs.last.controller
        return Row(
            name=r.name,
            state=state,
            severity=severity,
            since=since,
            age_s=None if r.last_mono is None else max(0.0, mono - r.last_mono),
            driver=None if s is None or gone else s.driver,  # lost: nobody can tell
            driver_detail=None if s is None or gone else s.driver_detail,
            mode=None if s is None else s.mode,
            p50_ms=None if lat is None else lat.p50_ms,
            p95_ms=None if lat is None else lat.p95_ms,
            latency_count=None if lat is None else lat.count,
            offset_bound_ms=bound,
            clock_note=clock_note,
            worst_topic=_worst_words(top),
            worst_health=None if worst is None else worst.health,
            controller=controller,
            progress=progress,
            grade=None if runs is None else _grade(runs.last, controller if s is None else s.controller),
            runs=None if s is None and runs is None else max(s.runs if s else 0, runs.count if runs else 0),
            bad=bad,
            bad_count=r.bad_count,
            note=note,
            rosbridge=None if s is None else s.rosbridge,
            tracker=None if s is None else s.tracker,
            namespace=None if s is None else s.namespace,
            auth=None if s is None else s.auth,
            pose=None if s is None else s.pose,
            velocity=None if s is None else s.velocity,
            figures_at=None if not gone or r.last_mono is None else wall - (mono - r.last_mono),
            flooding=None if flooding is None else round(flooding, 1),
        )

    def row_of(self, name: str, wall: float, mono: float) -> Row | None:
        r = self._robots.get(name)
        return None if r is None else self.row(r, wall, mono, self.silent_since(wall, mono))

    def _clock(self, lat: Latency | None) -> tuple[float | None, str | None]:
        if lat is None:
            return None, "no latency summary yet"
        robot = TimeSync(lat.sync_source, lat.sync_ok, None, lat.sync_error_ms)
        bound = one_way_bound_ms(self.console_sync, robot)
        if bound is not None:
            return round(bound, 3), None
        if not lat.sync_ok:
            return None, f"robot clock {'not synchronised' if lat.sync_ok is False else 'sync unknown'}"
        if self.console_sync is None or not self.console_sync.synchronised:
            return None, "this host's clock not synchronised"
        return None, "no error estimate"

    def view(
        self, wall: float, mono: float, pattern: str = "", session: str = "", error: str | None = None
    ) -> FleetView:
        silent = self.silent_since(wall, mono)
        rows = [self.row(r, wall, mono, silent) for r in self._robots.values()]
        counts = {s: 0 for s in (*STATES, "bad")}
        trouble: dict[str, list[str]] = {"lost": [], "bad": [], "flooding": [], "stale": [], "unknown": []}
        for row in rows:
            counts[row.state] += 1
            counts["bad"] += row.bad is not None
            if row.state in trouble:
                trouble[row.state].append(row.name)
            if row.bad is not None:
                trouble["bad"].append(row.name)
            if row.flooding is not None:
                trouble["flooding"].append(row.name)
        shown = sorted((r for r in rows if matches(r.name, pattern)), key=lambda r: (-r.severity, r.name))
        return FleetView(
            rows=tuple(shown),
            counts=tuple(counts.items()),
            total=len(rows),
            filter=pattern,
            ignored=len(self.ignored),
            unknown=self.unknown,
            flood_dropped=self.flood_dropped,
            now=wall,
            session=session,
            error=error,
            problems=tuple((what, tuple(sorted(names))) for what, names in trouble.items()),
            silent=silent,
        )


# -- the cells (one definition for the screen and --json) --------------------------------------------
COLUMNS = (
    "robot",
    "state",
    "driver",
    "p95",
    "clock",
    "worst topic",
    "controller",
    "last run",
    "runs",
    "note",
)


AGE_SHOWN_S = 2.0  # two status periods: an alive robot whose last payload is older is late


def clock_time(wall: float) -> str:
    return time.strftime("%H:%M:%S", time.localtime(wall))


def ago(seconds: float) -> str:
    s = int(seconds)
    if s < 120:
        return f"{s}s"
    if s < 7200:
        return f"{s // 60}m"
    return f"{s // 3600}h"


def state_cell(row: Row) -> str:
    """``alive`` / ``alive 3s`` (its last payload that old: late) / ``stale 12s`` / ``lost since 14:02:11``.
    An alive robot's age is shown once it is late (AGE_SHOWN_S): 0s and 1s flickering on every row told
    nothing and repainted the whole list twice a second."""
    if row.state in ("lost", "unknown"):
        return row.state if row.since is None else f"{row.state} since {clock_time(row.since)}"
    if row.age_s is None or (row.state == "alive" and row.age_s < AGE_SHOWN_S):
        return row.state
    return f"{row.state} {ago(row.age_s)}"


def figures_words(row: Row) -> str | None:
    """A lost row's figures are its last ones: ``figures as of 14:01:58, 2m old``."""
    if row.figures_at is None:
        return None
    return f"figures as of {clock_time(row.figures_at)}, {ago(row.age_s or 0.0)} old"


def flood_words(row: Row) -> str | None:
    return None if row.flooding is None else f"flooding: {row.flooding:.0f}/s, the excess dropped"


def note_cell(row: Row) -> str:
    if row.flooding is not None:
        return flood_words(row) or ""
    if row.bad is not None:
        return f"bad data: {row.bad}"
    return figures_words(row) or row.note or ""


def cells(row: Row) -> tuple[str, ...]:
    def ms(v: float | None) -> str:
        return "-" if v is None else f"{v:.3g} ms" if v < 100 else f"{v:.0f} ms"

    controller = row.controller or "-"
    if row.progress is not None:
        controller = f"{controller} {row.progress}"
    return (
        row.name,
        state_cell(row),
        row.driver or "-",
        ms(row.p95_ms),
        "-" if row.offset_bound_ms is None else f"±{ms(row.offset_bound_ms)}",
        row.worst_topic or "-",
        controller,
        row.grade or "-",
        "-" if row.runs is None else str(row.runs),
        note_cell(row),
    )


def console_argv(row: Row, token_file: str | None = None, ca_file: str | None = None) -> list[str] | str:
    """The single-robot console's command line for ``row`` (``arbiter-tui --robot-name NAME --rosbridge
    URL --tracker URL [--namespace NS]``), or why it cannot be opened, in one line."""
    if row.state == "lost":
        since = "" if row.since is None else f" since {clock_time(row.since)}"
        return f"{row.name} is lost{since}: nothing to open"
    if row.rosbridge is None:
        return f"{row.name} advertises no rosbridge URL (its backend runs --no-bridge, or no status yet)"
    argv = ["--robot-name", row.name, "--rosbridge", row.rosbridge]
    if row.tracker is not None:
        argv += ["--tracker", row.tracker]
    if row.namespace:
        argv += ["--namespace", row.namespace]
    if row.auth == "token":
        if token_file is None:
            return f"{row.name} wants its token: start the fleet with --token-file FILE"
        argv += ["--token-file", token_file]
    if ca_file is not None:
        argv += ["--ca-file", ca_file]
    return argv


def detail_lines(row: Row, now: float) -> list[str]:
    """The selected robot in full, for the screen's detail pane."""
    if row.state in ("lost", "unknown") and row.since is not None:
        state = f"{state_cell(row)} ({ago(max(0.0, now - row.since))} ago)"
    elif row.since is not None:
        state = f"{state_cell(row)} (announced since {clock_time(row.since)})"
    else:
        state = state_cell(row)
    lines = [f"{row.name}  {state}" + (f"  ·  {row.mode}" if row.mode else "")]
    drive = f"driver {row.driver or '-'}" + (f" ({row.driver_detail})" if row.driver_detail else "")
    if row.pose is not None:
        drive += f"  ·  pose ({row.pose[0]:+.2f}, {row.pose[1]:+.2f}, {row.pose[2]:+.2f})"
    if row.velocity is not None:
        drive += f" v {row.velocity[0]:+.2f} w {row.velocity[1]:+.2f}"
    lines.append(drive)
    if row.p95_ms is not None:
        lat = f"latency p50 {row.p50_ms:.3g} ms p95 {row.p95_ms:.3g} ms (n={row.latency_count})"
    else:
        lat = "latency: no command measured" if row.latency_count == 0 else "latency: no summary yet"
    clock = f"±{row.offset_bound_ms:.3g} ms" if row.offset_bound_ms is not None else (row.clock_note or "-")
    lines.append(f"{lat}  ·  clock offset bound {clock}")
    run = f"controller {row.controller or '-'}" + (f" {row.progress}" if row.progress else "")
    run += f"  ·  last run {row.grade or '-'}  ·  runs {'-' if row.runs is None else row.runs}"
    lines.append(f"worst topic {row.worst_topic or '-'}  ·  {run}")
    if row.rosbridge is not None:
        ns = f" --namespace {row.namespace}" if row.namespace else ""
        lines.append(f"Enter opens {row.rosbridge} {row.tracker or ''}{ns}".rstrip())
    if row.figures_at is not None:
        why = "the robot is lost" if row.state == "lost" else "this console's link is down"
        lines.append(f"{figures_words(row)}: not current ({why})")
    if row.flooding is not None:
        lines.append(f"{flood_words(row)} (its kinds' rates: one status a second, ...; flood.py)")
    if row.bad is not None:
        lines.append(f"bad data ({row.bad_count}): {row.bad}")
    elif row.note:
        lines.append(row.note)
    return lines


def history_words(answer: fleet.History | str) -> str:
    """One line of a robot's history answer (or why there is none)."""
    if isinstance(answer, str):
        return f"history: {answer}"
    lat = [e for e in answer.entries if isinstance(e, Latency) and e.p95_ms is not None]
    runs = [e for e in answer.entries if isinstance(e, Runs)]
    parts = [f"history ({answer.minutes:g} min): {len(answer.entries)} summaries"]
    if lat:
        lo, hi = min(e.p95_ms or 0.0 for e in lat), max(e.p95_ms or 0.0 for e in lat)
        parts.append(f"p95 {lo:.3g}-{hi:.3g} ms")
    if runs:
        parts.append(f"{len(runs)} runs, last {runs[-1].last.controller} {runs[-1].last.words()}")
    return ", ".join(parts)


PROBLEM_WORDS = {"lost": "lost", "bad": "bad data", "flooding": "flooding", "stale": "stale"}


def problem_line(view: FleetView, most: int = 4) -> str:
    """The robots in trouble by name, the worst kind first: ``lost 2: yard-02, yard-09 · bad data 1:
    lab-05 · stale 1: lab-03`` (at most ``most`` names a kind, then how many more)."""
    parts = []
    for what, names in view.problems:
        if names and what in PROBLEM_WORDS:
            shown = ", ".join(names[:most]) + (f" +{len(names) - most} more" if len(names) > most else "")
            parts.append(f"{PROBLEM_WORDS[what]} {len(names)}: {shown}")
    unknown = dict(view.counts).get("unknown", 0)
    if unknown and view.silent is not None:
        quiet = f"no robot heard since {clock_time(view.silent)}: the router or this network is silent"
        parts.insert(0, f"{unknown} unknown: {quiet}")
    elif unknown:
        parts.insert(0, f"{unknown} unknown: this console's link to its router is down")
    if parts:
        return " · ".join(parts)
    return f"all {view.total} alive, none in trouble" if view.total else "no robot announced yet"


def stop_words(answer: fleet.StopAnswer | str, at: float) -> str:
    """One line of what a robot answered a stop (or why it did not), with the time it was asked."""
    said = answer if isinstance(answer, str) else answer.words()
    return f"{clock_time(at)} {said}"
