"""What each widget shows, as frozen snapshots built from the console's state (pure: no Textual).

The frame sampler (``frames.py``) builds them from its sources (the link's telemetry, written on
roslibpy's thread; the control loop; the store; the tracker poller) into one frame at the UI rate.
Values are rounded to what the screen prints, so a snapshot equals the previous one exactly when the
screen would not change: the widget that picks it then does no work.
"""

from __future__ import annotations

import time
import unicodedata
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from arbiter_core import stats as S
from arbiter_core.controllers import MANUAL
from arbiter_core.kinematics import distance_error, heading_error
from arbiter_core.record import LatencyRecord
from arbiter_core.stats import Summary
from arbiter_core.timesync import TimeSync, one_way_bound_ms

from ..analytics.runs import AlgorithmSummary, RunSummary
from ..analytics.store import EMPTY_STATS, AnalyticsStats, AnalyticsStore
from ..control.loop import ControlLoop
from ..control.stop import StopScope
from ..latency.autonomy import RobotSideView
from ..latency.clocksync import MeterSummary
from ..latency.tracker_client import TrackerAnswer
from ..link.base import CONNECTED, DISCONNECTED, RECONNECTING, STARTING, Explains, Link

# -- the status line: parts by priority, fitted to a width ---------------------------------------------
SEP = " · "
DROPPED = "…"  # where parts were left out


@dataclass(frozen=True, slots=True)
class Part:
    """One part of a line, in its forms, longest first, each with its priority: 0 is never left out, and
    the form with the highest number gives way first (to the part's next form, or after its last, out of
    the line)."""

    forms: tuple[tuple[str, int], ...]

    @classmethod
    def of(cls, text: str, priority: int) -> Part:
        return cls(((text, priority),))


def cells(text: str) -> int:
    """Terminal columns ``text`` takes (wide East Asian characters take two)."""
    return sum(2 if unicodedata.east_asian_width(c) in "WF" else 1 for c in text)


def fit_parts(parts: Sequence[Part], width: int | None, sep: str = SEP) -> str:
    """``parts`` joined by ``sep`` in at most ``width`` columns (None: no limit). While the line is too
    long the least important form gives way (ties: the rightmost first), so every part shown is whole;
    each run of parts left out shows as one ``…``. If the parts that are never left out (priority 0) are
    too long on their own, the line ends at the last word that fits, then ``…``."""
    shown = [p for p in parts if p.forms and p.forms[0][0]]
    form = [0] * len(shown)  # index into each part's forms; len(forms): left out

    def line() -> str:
        out: list[str] = []
        for p, i in zip(shown, form, strict=True):
            if i < len(p.forms):
                out.append(p.forms[i][0])
            elif not out or out[-1] != DROPPED:
                out.append(DROPPED)
        return sep.join(out)

    text = line()
    while width is not None and cells(text) > width:
        live = [(p.forms[i][1], k) for k, (p, i) in enumerate(zip(shown, form, strict=True)) if p.forms[i:]]
        priority, k = max(live, default=(0, -1))
        if priority <= 0:
            return _cut(text, width)
        form[k] += 1
        text = line()
    return text


def _cut(text: str, width: int) -> str:
    """``text`` up to its last whole word that fits in ``width`` with `` …`` after it (a single word too
    long for the width: cut, then ``…``)."""
    best, used = "", 0
    for i, c in enumerate(text):
        if c == " ":
            head = text[:i].rstrip(" ·—")
            if head and cells(head) + 2 <= width:
                best = head
        used += cells(c)
        if used > width:
            break
    if best:
        return f"{best} {DROPPED}"
    out, used = "", 0
    for c in text:
        used += cells(c)
        if used > width - 1:
            break
        out += c
    return out + DROPPED if width > 0 else ""


def fit_fields(forms: Sequence[Sequence[str]], width: int | None, sep: str = " ") -> list[str]:
    """A value made of fields (``x +1.25``, ``y -0.50``, ``θ +0.60 rad``) in at most ``width`` columns
    (None or 0: no limit): its first form (fields joined by ``sep``) that fits, on one row; when none does,
    its last form on as many rows as it takes, broken between whole fields (a field wider than
    ``width`` on a row of its own)."""
    joined = [sep.join(fields) for fields in forms]
    if not width:
        return joined[:1]
    for text in joined:
        if cells(text) <= width:
            return [text]
    rows: list[str] = []
    for f in forms[-1]:
        if rows and cells(rows[-1] + sep + f) <= width:
            rows[-1] += sep + f
        else:
            rows.append(f)
    return rows


# priorities of the status line's parts (0: never left out; the highest goes first)
ALARM, RECORDING, API_DOWN, ALGORITHM, TARGET, HINT, DEPLOY = 0, 1, 2, 3, 4, 5, 6


@dataclass(frozen=True, slots=True)
class StatusView:
    """The status line on every screen."""

    link: str = STARTING
    target: str = ""
    deploy: str | None = None  # only once the tracker answered
    algorithm: str = MANUAL
    collecting: bool = False
    points: int = 0
    api: str | None = None  # "api UNREACHABLE" / "api …" (not answered yet); None when it answers
    error: str | None = None  # why the console could not start its link, or why the link is down
    warning: str | None = None  # e.g. "no odometry on /robot1/odom"
    observing: str | None = None  # observe mode: the observed controller's label
    robot: str = ""  # the robot's name (--robot-name, as the fleet passes it)
    recording: str | None = None  # the analytics show a file, not the live session

    @property
    def alarm(self) -> bool:
        return self.link in (DISCONNECTED, RECONNECTING) or self.error is not None or self.warning is not None

    def parts(self) -> list[Part]:
        """In the order shown. Kept longest: the link, why it is down, warnings, then whether samples are
        recorded (and how many), an unreachable API, the algorithm, where the backend is, the hint to
        press r, the deploy mode."""
        link = "DISCONNECTED (reconnecting)" if self.link == RECONNECTING else self.link
        parts = [Part.of(link, ALARM)]
        if self.robot:  # which robot this console drives: left out only after the sample count
            parts.append(Part.of(self.robot, RECORDING))
        if self.observing:  # the mode is never left out: keys do not do here what they do elsewhere
            parts.append(Part(((f"OBSERVING {self.observing}", ALARM),)))
        parts.append(Part.of(self.target, TARGET))
        if self.recording:  # the figures on screen are a file's: never taken for the live robot's
            parts.append(Part((("FILE " + self.recording, RECORDING), ("FILE", ALARM))))
        if self.error:
            parts.append(Part.of(self.error, ALARM))
        if self.deploy:
            parts.append(Part.of(f"deploy {self.deploy}", DEPLOY))
        if self.warning:
            parts.append(Part.of(self.warning, ALARM))
        parts.append(Part.of(self.algorithm, ALGORITHM))
        if self.collecting:
            parts.append(Part.of(f"● REC {self.points}", RECORDING))
        else:
            paused = f"paused {self.points}"
            parts.append(Part(((f"{paused} — r to record", HINT), (paused, RECORDING))))
        if self.api:
            parts.append(Part.of(self.api, API_DOWN if "UNREACHABLE" in self.api else DEPLOY))
        return parts

    def text(self, width: int | None = None) -> str:
        """The line, fitted to ``width`` columns (None: all of it): parts left out whole, marked ``…``."""
        return fit_parts(self.parts(), width)


@dataclass(frozen=True, slots=True)
class RobotView:
    """The control screen's panel: command, limits, pose, odometry, algorithm, mission, errors."""

    link_down: bool = False
    starting: bool = False
    stale: bool = False  # pose and odometry are the last received, not live
    v_cmd: float = 0.0
    w_cmd: float = 0.0
    speed: float = 0.0
    turn: float = 0.0
    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0
    v_odom: float = 0.0
    w_odom: float = 0.0
    algorithm: str = MANUAL
    state: str = "stopped"  # driving (a mission run) / teleop (a held key) / stopped
    mission: str = ""
    done: int = 0
    total: int = 0
    finished: str | None = None  # the last run completed: "done: 4/4 in 20.7 s", until a key or run
    goal: tuple[float, float] | None = None  # None in manual mode: there is no goal
    e_d: float | None = None
    e_th: float | None = None
    too_small: bool = False
    warning: str | None = None  # e.g. "no odometry on /robot1/odom"
    observing: str | None = None  # observe mode: what drives (its label) and what the console watches
    observed_run: int | None = None  # the observed run in progress
    robot_side: RobotSideView | None = None  # observe mode: the robot-side controller (g starts it)


@dataclass(frozen=True, slots=True)
class MapView:
    """The trajectory map: the trail (compared by its version, not point by point), pose, goal."""

    version: int = 0
    trail: tuple[tuple[float, float], ...] = field(default=(), compare=False)
    bounds: tuple[float, float, float, float] | None = None  # of the trail: x min, x max, y min, y max
    pose: tuple[float, float, float] | None = None
    goal: tuple[float, float] | None = None
    waypoints: tuple[tuple[float, float], ...] = ()
    stale: bool = False  # the pose is not live (link down, no odometry)


PLOT_ERRORS = 2000  # the error plot shows the newest samples, thinned to PLOT_MAX points
PLOT_TRAIL = 6000  # the trajectory plot: the newest samples, thinned to PLOT_MAX points per algorithm
PLOT_MAX = 600
PLOT_PERIOD_S = 1.0  # while samples stream in, the plots follow at most once a second (numbers: every update)


@dataclass(frozen=True, slots=True)
class Track:
    """One algorithm's part of the collected trajectory (thinned), for the trajectory plot."""

    algorithm: str
    x: tuple[float, ...]
    y: tuple[float, ...]


@dataclass(frozen=True, slots=True)
class AnalyticsView:
    """The analytics screen: the seed's nine stats over the ring, runs and algorithms over all their
    samples, and what the plots draw (compared by the store's version, not value by value)."""

    version: int = -1
    collecting: bool = False
    points: int = 0
    ring: int = 0  # the ring buffer's size (max_data_points)
    stats: AnalyticsStats = EMPTY_STATS
    runs: tuple[RunSummary, ...] = ()
    by_algorithm: tuple[AlgorithmSummary, ...] = ()
    error_t: tuple[float, ...] = field(default=(), compare=False)  # s since the first plotted sample
    errors: tuple[float, ...] = field(default=(), compare=False)  # distance error, m
    tracks: tuple[Track, ...] = field(default=(), compare=False)
    plot_version: int = 0  # advances when the plotted series were rebuilt
    plotted_at: float = field(default=float("-inf"), compare=False)  # monotonic s
    plotted_from: int = field(default=-1, compare=False)  # the store version the plots show
    waypoints: tuple[tuple[float, float], ...] = ()
    goal: tuple[float, float] | None = None
    source: str = ""  # a recording shown instead of the live session: what it is ("" = live)
    notes: tuple[str, ...] = ()  # what the recording's figures cannot vouch for
    plans: int = 0  # the recording's runs' reference paths (a journal's, an export's), each replan counted
    no_reference: str = ""  # why the recording's error stats have no reference ("" where they have one)

    @property
    def dropped_runs(self) -> tuple[RunSummary, ...]:
        """Runs whose samples the ring has partly or wholly dropped."""
        return tuple(r for r in self.runs if r.dropped > 0)


@dataclass(frozen=True, slots=True)
class LatencySnapshot:
    """The latency screen: the tracker's figures (polled) and this console's own (the meter)."""

    simulated: bool = False
    url: str = ""  # the tracker's
    polled: int = 0  # the poller's view version and failures: new data or a new failure
    failures: int = 0
    reachable: bool | None = None
    error: str | None = None
    kept: int | None = None  # records the tracker keeps (its own stats block's count); None: no answer
    stats_error: str | None = None  # the tracker's stats block was malformed (its records still shown)
    summary: Summary | None = None  # count/mean/min/max/p95/std over ``window``: the cards and the plot
    span_s: float = 0.0  # the time ``window`` covers
    deploy: str = "?"
    stale: int = 0
    rejected: int = 0
    max_command_age_ms: float | None = None
    window: tuple[float, ...] = field(default=(), compare=False)
    window_t: tuple[float, ...] = field(default=(), compare=False)  # receive times, epoch s
    records: tuple[LatencyRecord, ...] = field(default=(), compare=False)  # newest first, at most 30
    link_state: str = STARTING
    link_down: bool = False
    meter: MeterSummary = field(default_factory=MeterSummary)  # this console's round trips, offset, loss
    offset_warn_ms: float = 10.0
    local_sync: TimeSync | None = None  # this host's clock sync
    robot_sync: TimeSync | None = None  # the tracker host's (its /api/health)
    host_bound_ms: float | None = None  # both synchronised: their clocks are within this of each other
    sync_contradicted: bool = False  # ...but the measured offset says otherwise: the claim is not used


# -- builders ----------------------------------------------------------------------------------
def status_view(
    link: Link,
    target: str,
    loop: ControlLoop,
    store: AnalyticsStore,
    tracker: TrackerAnswer | None,
    simulated: bool,
    error: str | None = None,
    now: float | None = None,
    observing: str | None = None,
    recording: str | None = None,
    driving: str | None = None,
    robot: str = "",
) -> StatusView:
    """``driving``: what drives the robot when the console's loop does not (observe mode's robot-side
    controller), shown instead of the loop's algorithm."""
    api = deploy = None
    if not simulated and tracker is not None:
        reach = tracker.reachable
        if reach:
            deploy = tracker.deploy_mode  # shown once the tracker answered: that says the API is up
        else:
            api = "api …" if reach is None else "api UNREACHABLE"
    return StatusView(
        link=link.state,
        target=target,
        deploy=deploy,
        algorithm=driving or loop.algorithm,
        collecting=store.is_collecting,
        points=len(store),
        api=api,
        error=error or (link.error if isinstance(link, Explains) else None),
        warning=odometry_warning(link, time.monotonic() if now is None else now),
        observing=observing,
        recording=recording,
        robot=robot,
    )


def odometry_warning(link: Link, now: float) -> str | None:
    """``no odometry on TOPIC`` while the link is up and odometry has not come for a while, with the
    cause when the server named one (e.g. the topic has another type)."""
    if link.state == CONNECTED and link.telemetry.odometry_missing(now):
        cause, topic = (
            (link.odometry_problem, link.topic_odom) if isinstance(link, Explains) else (None, "/odom")
        )
        return f"no odometry on {topic}" + (f": {cause}" if cause else "")
    return None


def odometry_stale(link: Link, now: float) -> bool:
    """The pose and odometry shown are not live: the link is down, or odometry stopped coming."""
    if link.state in (DISCONNECTED, RECONNECTING):
        return True
    return link.state == CONNECTED and link.telemetry.odometry_missing(now)


@dataclass(frozen=True, slots=True)
class Observed:
    """Observe mode, for the panel: what drives and what the console watches, the observed run's goal."""

    label: str
    goal: tuple[float, float] | None = None
    run: int | None = None
    robot_side: RobotSideView | None = None


def observe_banner(label: str, watched: Sequence[str], scope: StopScope) -> str:
    """Observe mode's banner on every screen: what is observed, what a stop does (first: it matters most,
    and a narrow terminal cuts the line's end), what the console watches."""
    stop = ["the console's keys"]
    if scope.robot_side:
        stop.append("the robot-side controller")
    if scope.actions:
        stop.append(f"{len(scope.actions)} action servers' goals")
    if scope.zero_topic:
        stop.append(f"zero on {scope.zero_topic}")
    return f"OBSERVING {label} · a stop key stops {', '.join(stop)} · watching {' '.join(watched)}"


def robot_view(
    link: Link,
    loop: ControlLoop,
    too_small: bool = False,
    now: float | None = None,
    observed: Observed | None = None,
) -> RobotView:
    pose, v_odom, w_odom, _lat = link.telemetry.snapshot()
    now = time.monotonic() if now is None else now
    plan = loop.plan(pose)  # what g drives: the goal shown is the one it drives to
    goal = None if plan is None else plan.goal
    if observed is not None:  # the goal shown is the observed controller's, never a console mission's
        plan, goal = None, observed.goal
    e_d = e_th = None
    if goal is not None:
        e_d, e_th = round(distance_error(pose, goal), 2), round(heading_error(pose, goal), 2)
    state = "driving" if loop.running else ("teleop" if loop.teleop.moving else "stopped")
    mission = plan or loop.mission
    v, w = loop.command
    down = link.state in (DISCONNECTED, RECONNECTING)
    return RobotView(
        link_down=down,
        starting=link.state == STARTING,
        stale=odometry_stale(link, now),
        v_cmd=round(v, 2),
        w_cmd=round(w, 2),
        speed=round(loop.teleop.speed, 2),
        turn=round(loop.teleop.turn, 2),
        x=round(pose.x, 2),
        y=round(pose.y, 2),
        theta=round(pose.theta, 2),
        v_odom=round(v_odom, 2),
        w_odom=round(w_odom, 2),
        algorithm=loop.algorithm,
        state=state,
        mission=loop.mission_label,
        done=len(mission.waypoints) if mission.done else mission.index,
        total=len(mission.waypoints),
        finished=None if loop.running else loop.finished,
        goal=None if goal is None else (round(goal[0], 2), round(goal[1], 2)),
        e_d=e_d,
        e_th=e_th,
        too_small=too_small,
        warning=odometry_warning(link, now),
        observing=None if observed is None else observed.label,
        observed_run=None if observed is None else observed.run,
        robot_side=None if observed is None else observed.robot_side,
    )


def map_view(
    link: Link,
    loop: ControlLoop,
    previous: MapView | None = None,
    now: float | None = None,
    observed: Observed | None = None,
) -> MapView:
    pose = link.telemetry.snapshot()[0]
    version = loop.trail.version
    if previous is not None and previous.version == version:
        trail, bounds = previous.trail, previous.bounds
    else:
        trail = tuple(loop.trail.points)
        bounds = bounds_of(trail)
    plan = loop.plan(pose)  # the waypoints where g takes the robot, not the mission's own frame
    goal = None if plan is None else plan.goal
    if observed is not None:  # observing: the observed controller's goal, no mission of the console's
        plan, goal = None, observed.goal
    return MapView(
        version=version,
        trail=trail,
        bounds=bounds,
        pose=(round(pose.x, 2), round(pose.y, 2), round(pose.theta, 1)),
        goal=goal,
        waypoints=() if plan is None else tuple(plan.waypoints),
        stale=odometry_stale(link, time.monotonic() if now is None else now),
    )


def bounds_of(points: Sequence[tuple[float, float]]) -> tuple[float, float, float, float] | None:
    """(x min, x max, y min, y max) of the points; None when there are none."""
    if not points:
        return None
    xs = [p[0] for p in points]
    ys = [p[1] for p in points]
    return min(xs), max(xs), min(ys), max(ys)


def thin(n: int, most: int) -> slice:
    """Every k-th of ``n`` samples so that at most ``most`` remain, always ending with the newest."""
    step = max(1, -(-n // most))
    return slice((n - 1) % step, n, step)


def analytics_view(
    store: AnalyticsStore,
    previous: AnalyticsView | None = None,
    loop: ControlLoop | None = None,
    now: float | None = None,
) -> AnalyticsView:
    """Recomputed only when the store changed (its version), whatever the UI rate. The plots' series
    come from the newest samples only (the cost does not grow with the ring's size) and, while samples
    stream in, are rebuilt at most every ``PLOT_PERIOD_S``: painting a plot costs more than the numbers."""
    now = time.monotonic() if now is None else now
    version = store.version
    waypoints: tuple[tuple[float, float], ...] = ()
    goal = None
    if loop is not None and loop.algorithm != MANUAL:
        waypoints, goal = tuple(loop.mission.waypoints), loop.mission.goal
    if previous is not None and previous.version == version:
        plots_due = previous.plotted_from != version and now - previous.plotted_at >= PLOT_PERIOD_S
        if not plots_due:
            if (previous.waypoints, previous.goal) == (waypoints, goal):
                return previous
            return replace(previous, waypoints=waypoints, goal=goal)
    runs = store.runs()
    points = len(store)
    replot = (
        previous is None
        or not store.is_collecting  # paused or cleared: show exactly what is held
        or points < previous.points
        or len(runs) != len(previous.runs)  # a run began: its first samples show at once
        or now - previous.plotted_at >= PLOT_PERIOD_S
    )
    view = AnalyticsView(
        version=version,
        collecting=store.is_collecting,
        points=points,
        ring=store.max_data_points,
        stats=store.stats(),
        runs=runs,
        by_algorithm=store.runs_by_algorithm(),
        waypoints=waypoints,
        goal=goal,
    )
    if not replot:
        assert previous is not None
        return replace(view, error_t=previous.error_t, errors=previous.errors, tracks=previous.tracks,
                       plot_version=previous.plot_version, plotted_at=previous.plotted_at,
                       plotted_from=previous.plotted_from)  # fmt: skip
    cols, codes, names = store.tail(PLOT_TRAIL)
    t, e_d = cols["timestamp"][-PLOT_ERRORS:], cols["distanceError"][-PLOT_ERRORS:]
    pick = thin(t.size, PLOT_MAX)
    t0 = float(t[0]) if t.size else 0.0
    tracks = []
    for code in dict.fromkeys(codes.tolist()):
        idx = np.flatnonzero(codes == code)
        idx = idx[thin(idx.size, PLOT_MAX)]
        tracks.append(Track(names[code], tuple(cols["x"][idx].tolist()), tuple(cols["y"][idx].tolist())))
    return replace(
        view,
        error_t=tuple(((t[pick] - t0) / 1000.0).tolist()),
        errors=tuple(e_d[pick].tolist()),
        tracks=tuple(tracks),
        plot_version=(previous.plot_version + 1) if previous is not None else 1,
        plotted_at=now,
        plotted_from=version,
    )


def latency_snapshot(
    view: TrackerAnswer | None, link: Link, offset_warn_ms: float, simulated: bool, url: str = ""
) -> LatencySnapshot:
    state = link.state
    if simulated or view is None:
        return LatencySnapshot(simulated=True, link_state=state, offset_warn_ms=offset_warn_ms)
    # both hosts say they are synchronised: their clocks are within the sum of their errors, a bound on
    # the one-way figures, unless the round trips measure an offset beyond it (a claim not to trust)
    host = one_way_bound_ms(view.local_sync, view.robot_sync)
    est = link.telemetry.meter.offset()
    contradicted = host is not None and est is not None and abs(est.offset_ms) - est.uncertainty_ms > host
    return LatencySnapshot(
        url=url,
        polled=view.version,
        failures=view.failures,
        reachable=view.reachable,
        error=view.error,
        kept=view.stats.count if view.reachable and view.stats is not None else None,
        stats_error=view.stats_error,
        summary=S.summarize(view.window) if view.window else None,
        span_s=(view.window_t[-1] - view.window_t[0]) if len(view.window_t) > 1 else 0.0,
        deploy=view.deploy_mode,
        stale=view.stale,
        rejected=view.rejected,
        max_command_age_ms=view.max_command_age_ms,
        window=view.window,
        window_t=view.window_t,
        records=tuple(reversed(view.records))[:30],
        link_state=state,
        link_down=state in (DISCONNECTED, RECONNECTING),
        meter=link.telemetry.meter.summary(host_error_ms=None if contradicted else host).shown(),
        offset_warn_ms=offset_warn_ms,
        local_sync=view.local_sync,
        robot_sync=view.robot_sync,
        host_bound_ms=host,
        sync_contradicted=contradicted,
    )
