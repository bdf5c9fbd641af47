"""Widgets that show one snapshot each (``views.py``): a reactive ``view``, rendered only when it changed.

Each widget is bound (``data_bind``) to its screen's ``frame`` and picks its own typed part of it
(``pick``); Textual compares the new part with the old and calls nothing when they are equal, so a widget
whose data did not change does no work. ``renders`` counts render calls (tests check that equal data
costs nothing).
"""

from __future__ import annotations

import re
from typing import Generic, TypeVar

from rich.cells import cell_len
from rich.text import Text
from textual.reactive import reactive
from textual.widget import Widget

from arbiter_core.controllers import goal_driver
from arbiter_core.timesync import TimeSync

from ...analytics.labels import STAT_LABELS, format_stat
from ...analytics.store import STATS_FIELDS
from ...control.teleop import legend_compact
from ...latency.clocksync import OffsetEstimate
from ...session.frames import Frame
from ...session.views import AnalyticsView, LatencySnapshot, RobotView, StatusView, fit_fields
from ..perf import give_way

LINK_DOWN = (  # two lines of the 36 columns inside the panel: the rows below stay in view
    "LINK DOWN: nothing is sent.\nThe robot stops on its own timeout.\n"
)
STALE = "*"  # marks a value that is the last received, not live
LABEL = 9  # the control panel's label column: "Command  "
KEY_HELP = legend_compact()
FIT = "fit"  # the dashboard's class for a widget that lays its figures out to its width, never wrapping one
PART = " · "  # what separates the parts of a line of figures: where a line may break
INDENT = "  "  # a line's continuation, when it was broken to fit
FIELDS = re.compile(r"(?:(?:on|at|g:) )?\S+")  # a run's fields: "stanley", "on corner", "at 1/2"


def _breaks(plain: str, start: int) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
    """Where a line may break after ``start``, as (end of this row, start of the next): between its parts
    (``PART``); else after a comma or a closing bracket outside brackets (never inside an interval like
    ``[0.000, 0.590]``)."""
    parts = [(i, i + len(PART)) for i in range(start + 1, len(plain)) if plain.startswith(PART, i)]
    others, depth = [], 0
    for i, ch in enumerate(plain):
        depth = max(0, depth + (ch in "[(") - (ch in "])"))
        if i > start and depth == 0 and ch in ",])" and plain.startswith(" ", i + 1):
            others.append((i + 1, i + 2))
    return parts, others


def fit_lines(text: Text, width: int) -> Text:
    """``text`` with each line wider than ``width`` broken where a part ends (``PART``), else after a
    comma or an interval: a figure stays beside its label. A part wider than ``width`` on its own is
    left to wrap. The rows after the first of a line are indented."""
    if width <= 0:
        return text
    out: list[Text] = []
    for line in text.split("\n"):
        plain, start, room = line.plain, 0, width
        while cell_len(plain[start:]) > room:
            parts, others = _breaks(plain, start)
            fit = [b for b in parts if cell_len(plain[start : b[0]]) <= room] or [
                b for b in others if cell_len(plain[start : b[0]]) <= room
            ]
            if fit:
                end, after = fit[-1]
            elif parts or others:
                end, after = (parts or others)[0]
            else:
                break
            out.append(Text(INDENT) + line[start:end] if start else line[start:end])
            start, room = after, width - len(INDENT)
        out.append(Text(INDENT) + line[start:] if start else line[start:])
    return Text("\n").join(out)


def fitted(widget: Widget, text: Text) -> Text:
    """``text`` fitted to ``widget``'s width, on as many rows as the same lines have ever taken at this
    width (blank rows below when they take fewer); when that changes, a new layout (a ``height: auto``
    widget is sized when laid out, not when its figures change: a line that came with the first round
    trip was otherwise cut until the next resize). The same lines never take fewer rows: figures whose
    widths varied around the width changed the height every few seconds, and each new layout repaints
    the whole screen."""
    width = widget.content_size.width
    shape = (width, text.plain.count("\n"))  # the same lines at the same width: their rows never shrink
    text = fit_lines(text, width)
    rows = text.plain.count("\n") + 1
    last_shape, last_rows = getattr(widget, "_fit", (None, rows))
    most = max(last_rows, rows) if shape == last_shape else rows
    if most != last_rows:
        widget.refresh(layout=True)
    widget._fit = (shape, most)  # type: ignore[attr-defined]  # kept on the widget, whichever it is
    if rows < most:
        text.append("\n" * (most - rows))
    return text


V = TypeVar("V")


class Bound(Widget, Generic[V]):
    """A widget that shows one part of the frame (``pick``): bind it with ``.data_bind(BaseScreen.frame)``."""

    frame: reactive[Frame] = reactive(Frame, repaint=False)
    renders = 0

    def pick(self, frame: Frame) -> V:
        raise NotImplementedError

    def watch_frame(self, frame: Frame) -> None:
        self.view = self.pick(frame)  # a reactive ``view`` on each subclass: equal values do nothing

    def render(self) -> Text:
        self.renders += 1
        give_way.now()
        return self.draw()

    def draw(self) -> Text:
        raise NotImplementedError


class StatusLine(Bound[StatusView]):
    DEFAULT_CSS = """
    StatusLine { dock: top; height: 1; background: $panel; color: $text; padding: 0 1; }
    StatusLine.alarm { background: $error; text-style: bold; }
    """
    view: reactive[StatusView] = reactive(StatusView)

    def pick(self, frame: Frame) -> StatusView:
        return frame.status

    def watch_view(self, view: StatusView) -> None:
        self.set_class(view.alarm, "alarm")

    def draw(self) -> Text:
        # parts that do not fit are left out whole (views.fit_parts), never cut mid-word at the edge
        return Text(self.view.text(self.size.width or None), no_wrap=True, overflow="ellipsis")


class RobotPanel(Bound[RobotView]):
    view: reactive[RobotView] = reactive(RobotView)
    _rows = 0  # rows the last paint took: a height: auto widget is sized when laid out

    def pick(self, frame: Frame) -> RobotView:
        return frame.robot

    def draw(self) -> Text:
        t = self.draw_rows()
        rows = t.plain.count("\n") + 1
        if rows != self._rows:  # a row more or less (a state row, the link down): laid out again
            self._rows = rows
            self.refresh(layout=True)
        return t

    def draw_rows(self) -> Text:
        r = self.view
        t = Text()
        if r.link_down:
            t.append(LINK_DOWN, "bold red")
        elif r.starting:
            t.append("Starting: connecting to the robot…\n", "bold yellow")
        if r.too_small:
            t.append("Terminal too small: robot stopped.\n", "bold red")
        if r.warning:
            t.append(f"{r.warning}\n", "bold red")
        v, w = f"v {r.v_cmd:+.2f}", f"ω {r.w_cmd:+.2f}"
        self.row(t, "Command", [[f"{v} m/s", f"{w} rad/s"], [v, w]], sep="  ")
        self.row(t, "Max", [[f"speed {r.speed:.2f}", f"turn {r.turn:.2f}"]], sep="  ")
        # Pose and odometry that are not live are marked (a star and dim, not colour alone) and kept:
        # where the robot was last seen is still worth knowing.
        mark, look = (STALE, "dim") if r.stale else ("", "")
        x, y, theta = f"x {r.x:+.2f}", f"y {r.y:+.2f}", f"θ {r.theta:+.2f}"
        self.row(t, f"Pose{mark}", [[x, y, f"{theta} rad"], [x, y, theta]], look)  # narrow: no unit
        self.row(t, f"Odom{mark}", [[f"v {r.v_odom:+.2f}", f"ω {r.w_odom:+.2f}"]], look, sep="  ", end="")
        t.append("  * stale\n" if r.stale else "\n", "bold yellow")
        if r.observing is not None:
            self.draw_observed(t, r)
        else:
            if self.fits(f"{r.algorithm} ({r.state})"):
                self.row(t, "Algo", [[r.algorithm, f"({r.state})"]])
            else:  # narrow: the state on a row of its own, never a word alone under the name
                self.row(t, "Algo", [[r.algorithm]])
                self.row(t, "State", [[r.state]])
            if r.finished is not None:
                self.row(t, "Mission", [[r.mission, r.finished]], "bold green")
            else:
                self.row(t, "Mission", [[r.mission, f"{r.done}/{r.total}"]])
        none = "none (manual)" if r.observing is None else "none (no observed run)"
        self.row(t, "Goal", [[none if r.goal is None else f"({r.goal[0]:+.2f}, {r.goal[1]:+.2f})"]])
        if r.e_d is None or r.e_th is None:
            self.row(t, "Errors", [["—"]], end="")
        else:
            self.row(t, "Errors", [[f"e_d {r.e_d:.2f} m", f"e_θ {r.e_th:+.2f} rad"]], sep="  ", end="")
        if r.observing is not None:
            t.append("\n")
            self.draw_robot_side(t, r)
        return t

    def draw_robot_side(self, t: Text, r: RobotView) -> None:
        """Observe mode: the robot-side controller, each line broken between whole words to fit (at 80
        columns "pure_pursuit on corner at 0/2" did not, and ran on under the label)."""
        rs = r.robot_side
        rows: list[tuple[str, str, str]] = []  # (label, text, style)
        if rs is None or not rs.known:
            rows.append(("Robot", "robot-side: not asked yet", ""))
        elif not rs.enabled:
            rows.append(("Robot", rs.text, "dim"))
        else:
            rows.append(("Robot", rs.text, "bold green" if rs.running else ""))
            if rs.run:
                rows.append(("", rs.run, "" if rs.running else "dim"))
            if not rs.running:
                rows.append(("", f"g: {goal_driver(r.algorithm)} on {r.mission}", "dim"))
        for i, (label, text, style) in enumerate(rows):
            fields = FIELDS.findall(text)  # "on corner", "at 0/2": a word with the one it governs
            self.row(t, label, [fields], style, end="\n" if i < len(rows) - 1 else "")

    def room(self) -> int | None:
        """Columns for a row's value, right of its label (None: not laid out yet, no limit)."""
        width = self.content_size.width
        return max(1, width - LABEL) if width else None

    def fits(self, value: str) -> bool:
        room = self.room()
        return room is None or cell_len(value) <= room

    def row(
        self, t: Text, label: str, forms: list[list[str]], style: str = "", sep: str = " ", end: str = "\n"
    ) -> None:
        """``label`` and its value in the first form that fits the panel, else broken between whole fields,
        the rows after the first under the value (``views.fit_fields``)."""
        t.append(f"{label:<{LABEL}}", "bold")
        t.append(f"\n{'':<{LABEL}}".join(fit_fields(forms, self.room(), sep)) + end, style)

    @staticmethod
    def draw_observed(t: Text, r: RobotView) -> None:
        """Observe mode: what drives (the banner says what the console watches), the console's own keys'
        state, and the observed run (no console mission: g starts the robot-side controller, when the
        backend runs one)."""
        t.append("Observe  ", "bold")
        t.append(f"{r.observing}", "bold magenta")
        t.append(f" (keys: {r.state})\n")
        t.append("Run      ", "bold")
        run = r.observed_run
        t.append("none yet (waits for a goal)\n" if run is None else f"{run}\n")


class StatsCards(Bound[AnalyticsView]):
    VALUE = 11  # the fitted cards' value column at least: "0.341 rad/s"
    view: reactive[AnalyticsView] = reactive(AnalyticsView)

    def pick(self, frame: Frame) -> AnalyticsView:
        return frame.analytics

    def draw(self) -> Text:
        if self.has_class(FIT):
            return self.draw_fitted()
        stats, why = self.view.stats, self.view.no_reference
        t = Text()
        for i, name in enumerate(STATS_FIELDS):
            t.append(f"{STAT_LABELS[name].short:>10} ", "bold")
            t.append(f"{format_stat(name, getattr(stats, name), no_reference=why):<16}")
            if i % 3 == 2 and i < len(STATS_FIELDS) - 1:
                t.append("\n")
        return t

    def draw_fitted(self) -> Text:
        """The dashboard's cards: as many to a row as fit the width (rows balanced), each label on the row
        of its value, columns as wide as the longest label and value need (values: at least ``VALUE``, so
        the cards do not move as the figures grow)."""
        stats, why = self.view.stats, self.view.no_reference
        cards = [
            (STAT_LABELS[n].short, format_stat(n, getattr(stats, n), no_reference=why)) for n in STATS_FIELDS
        ]
        label = max(cell_len(k) for k, _v in cards)
        value = max(self.VALUE, *(cell_len(v) for _k, v in cards))
        card = label + 1 + value + 2
        width = self.content_size.width or 3 * card
        per_row = max(1, min(len(cards), (width + 2) // card))
        rows = -(-len(cards) // per_row)
        per_row = -(-len(cards) // rows)
        t = Text()
        for i, (k, v) in enumerate(cards):
            t.append(f"{k:>{label}} ", "bold")
            last = i % per_row == per_row - 1 or i == len(cards) - 1
            t.append(v if last else f"{v:<{value + 2}}")
            if last and i < len(cards) - 1:
                t.append("\n")
        return t


def fmt_ms(value: object) -> str:
    if value is None:
        return "N/A"
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return f"{value:.3f} ms"
    return "?"


def fmt_signed(value: float | None) -> str:
    return "N/A" if value is None else f"{value:+.3f} ms"


WARN_AHEAD_S = 600.0  # the drift forecast warns this far ahead of the offset crossing --offset-warn-ms


def fmt_interval(lo: float | None, hi: float | None) -> str:
    """Where the truth lies: ``[0.000, 0.612]`` (ms)."""
    return "" if lo is None or hi is None else f"[{lo:.3f}, {hi:.3f}]"


def fmt_duration(seconds: float) -> str:
    return f"~{seconds:.0f} s" if seconds < 90 else f"~{seconds / 60:.0f} min"


def fmt_clock(off: OffsetEstimate | None) -> str:
    """``clock +250.3 ms ± 0.4 ms, drifting +498 ppm (30 ms/min)``."""
    if off is None:
        return "clock offset N/A"
    text = f"clock {off.offset_ms:+.1f} ms ± {off.uncertainty_ms:.1f} ms"
    if off.drift_ppm is None or off.drift_bound_ppm is None:
        text += ", drift not known yet"
    elif abs(off.drift_ppm) <= off.drift_bound_ppm:
        text += f", drift within ±{off.drift_bound_ppm:.0f} ppm"
    else:
        per_min = off.drift_ppm * 60 / 1000
        rate = f"{per_min:.0f}" if abs(per_min) >= 1 else f"{per_min:.2f}"
        text += f", drifting {off.drift_ppm:+.0f} ppm ({rate} ms/min)"
    if off.steps:
        text += f", {off.steps} step{'s' if off.steps > 1 else ''}"
    return text


def fmt_sync(t: TimeSync | None) -> str:
    return "not said" if t is None else t.short()


CARDS = (("count", "count"), ("mean_ms", "mean"), ("min_ms", "min"), ("max_ms", "max"), ("p95_ms", "p95"),
         ("stddev_ms", "stddev"))  # fmt: skip


class TrackerLine(Bound[LatencySnapshot]):
    view: reactive[LatencySnapshot] = reactive(LatencySnapshot)

    def pick(self, frame: Frame) -> LatencySnapshot:
        return frame.latency

    def draw(self) -> Text:
        v = self.view
        state = Text()
        if v.simulated:
            state.append("Client-side simulation: no network path, latency N/A", "bold")
        elif v.reachable is None:
            state.append("Polling the tracker…", "bold")
        elif not v.reachable:
            at = f" at {v.url}" if v.url else ""
            state.append(f"TRACKER UNREACHABLE{at}: {v.error} — retrying every 0.5 s", "bold red")
        else:
            state.append("tracker reachable", "bold green")
            kept = v.kept
            state.append(f" · deploy mode {v.deploy}" + ("" if kept is None else f" · tracker keeps {kept}"))
            if v.stale:  # the robot ignores these: the operator must know why it does not move
                limit = "" if v.max_command_age_ms is None else f" > {v.max_command_age_ms:g} ms"
                state.append(f" · {v.stale} STALE{limit}, not forwarded", "bold red")
            if v.rejected:
                state.append(f" · {v.rejected} rejected", "bold yellow")
            if v.stats_error:
                state.append(f" · its stats block is malformed ({v.stats_error})", "bold yellow")
        return fitted(self, state) if self.has_class(FIT) else state


class TrackerCards(Bound[LatencySnapshot]):
    """One-way latency over the console's window of the tracker's records: the same records, and so the
    same p95, as the plot and the histogram beside it."""

    view: reactive[LatencySnapshot] = reactive(LatencySnapshot)

    def pick(self, frame: Frame) -> LatencySnapshot:
        return frame.latency

    def draw(self) -> Text:
        s = self.view.summary
        cards = Text()
        span = "" if s is None else f", {self.view.span_s:.0f} s"
        cards.append(f"one-way, last {0 if s is None else s.count} commands{span}\n", "bold")
        for i, (key, label) in enumerate(CARDS):
            value = None if s is None else getattr(s, key.removesuffix("_ms"))
            text = "N/A" if value is None else (str(value) if key == "count" else fmt_ms(value))
            cards.append(f"{label:>7} ", "bold")
            cards.append(f"{text:<14}")
            if i == 2:
                cards.append("\n")
        return cards


class ClientLine(Bound[LatencySnapshot]):
    """This console's own view: round trip, offset (NTP method), corrected one-way, loss."""

    view: reactive[LatencySnapshot] = reactive(LatencySnapshot)

    def pick(self, frame: Frame) -> LatencySnapshot:
        return frame.latency

    def watch_view(self, view: LatencySnapshot) -> None:
        self.display = not view.simulated

    def draw(self) -> Text:
        out = self.draw_lines()
        return fitted(self, out) if self.has_class(FIT) else out

    def draw_lines(self) -> Text:
        v = self.view
        out = Text()
        if v.simulated:
            return out
        s = v.meter
        out.append("this console", "bold")
        if v.link_down:
            down = f" · ROSBRIDGE LINK {v.link_state}: no commands, no round trips"
            out.append(f"{down} · sent {s.sent} · lost {s.lost}", "bold red")
            return out
        if not s.n:
            out.append(f" · no round trips yet · sent {s.sent} · lost {s.lost}")
            return out
        out.append(f" · rtt p50 {fmt_ms(s.rtt_p50_ms)} p95 {fmt_ms(s.rtt_p95_ms)}")
        out.append(f" · jitter {fmt_ms(s.jitter_ms)} · raw one-way p50 {fmt_ms(s.raw_p50_ms)}\n")
        out.append("one-way corrected", "bold")
        p50 = fmt_interval(s.corrected_p50_lo_ms, s.corrected_p50_hi_ms)
        p95 = fmt_interval(s.corrected_p95_lo_ms, s.corrected_p95_hi_ms)
        out.append(f" p50 {fmt_ms(s.corrected_p50_ms)} {p50} p95 {fmt_ms(s.corrected_p95_ms)} {p95}")
        if s.host_bound_used:
            out.append(" (bounded by both hosts' clock sync)")
        out.append("\n")
        off = s.offset
        out.append(fmt_clock(off))
        out.append(f" · negative {s.negative} · lost {s.lost_in_window} in 10 s ({s.lost} total)")
        if s.late:
            out.append(f" · late {s.late} (queued, not lost)")
        if v.local_sync is not None or v.robot_sync is not None:
            here, there = fmt_sync(v.local_sync), fmt_sync(v.robot_sync)
            out.append(f"\ntime sync: this host {here}, robot host {there}")
            if v.sync_contradicted:
                out.append(" · CONTRADICTED by the measured offset: not used", "bold yellow")
            elif v.host_bound_ms is not None:
                out.append(f" · clocks within ±{v.host_bound_ms:.2f} ms", "green")
        warn = v.offset_warn_ms
        if off is not None and off.significant(warn):
            out.append(
                f"\nCLOCK OFFSET {off.offset_ms:+.1f} ms exceeds {warn:g} ms: raw one-way figures include it",
                "bold red",
            )
        elif off is not None:
            until = off.seconds_until(warn)
            if until is not None and until <= WARN_AHEAD_S:
                crossing = f"\nCLOCK DRIFT: offset crosses {warn:g} ms in {fmt_duration(until)}"
                out.append(crossing, "bold yellow")
        return out
