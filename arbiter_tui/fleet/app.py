"""The fleet screen: one line per robot, the worst first, the selected one in full below.

The screen takes a frozen ``FleetView`` from its source every ``REFRESH_S`` (the Zenoh callbacks only
change the model; nothing is drawn on their threads) and hands it to the list by ``data_bind``; the
list draws only the rows that fit (200 robots cost what 20 do). ``/`` filters by name glob, Enter opens
the single-robot console on the selected robot (the app suspends, the console runs in this terminal,
the fleet comes back when it quits), ``h`` asks the robot's history on a worker thread. ``space`` or
``ctrl+k`` asks the robot drawn selected to stop (``arbiter/<name>/stop``), ``S`` twice every robot shown;
the row's note says what each answered, for ``STOP_NOTE_S``.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

from rich.cells import cell_len
from rich.text import Text
from textual import events, on, work
from textual.app import App, ComposeResult, SuspendNotSupported
from textual.binding import Binding
from textual.driver import Driver
from textual.geometry import Region
from textual.message import Message
from textual.reactive import reactive
from textual.screen import Screen
from textual.strip import Strip
from textual.widget import Widget
from textual.widgets import Footer, Input, Static

from arbiter_core import fleet

from ..session.views import fit_fields
from ..terminal import fewer_bytes
from .rows import (
    BAD,
    COLUMNS,
    OK,
    STALE,
    FleetView,
    Row,
    cells,
    clock_time,
    console_argv,
    detail_lines,
    history_words,
    problem_line,
    stop_words,
)

REFRESH_S = 0.5
PARTS = ("  ·  ", " · ")  # where a head or detail line breaks to fit its width (then between words)
GO_ON = "  "  # a broken line's continuation
SEP = 1  # space between columns
# column -> width; shown in PRIORITY order while they fit, "note" takes the rest (at least NOTE_MIN)
WIDTHS = {"robot": 12, "state": 22, "driver": 8, "p95": 8, "clock": 9, "worst topic": 24,
          "controller": 24, "last run": 34, "runs": 4}  # fmt: skip
PRIORITY = ("robot", "state", "driver", "p95", "worst topic", "clock", "controller", "last run", "runs")
NOTE_MIN = 22
STATE_STYLES = {"lost": "bold red", "stale": "yellow", "alive": "green", "unknown": "bold magenta"}
LAST_FIGURES = ("driver", "p95", "clock", "worst topic", "controller", "last run", "runs")
CONFIRM_S = 3.0  # "stop all shown" asks for a second press within this
STOPS_AT_ONCE = 32  # stop questions in flight at once (each waits at most fleet.STOP_TIMEOUT_S)
STOP_NOTE_S = 10.0  # a stop's answer stays in its row's note this long (then the row's own note again)


@dataclass(frozen=True)
class StopNote:
    """What a robot answered its last stop (or why it did not), in its row's note until ``until`` (on the
    views' clock, ``FleetView.now``); ``failed``: not stopped for sure (shown in red)."""

    words: str
    failed: bool
    until: float


def layout(width: int) -> list[tuple[int, int]]:
    """(index into COLUMNS, width) of the columns shown at ``width``, in COLUMNS order; the note last."""
    shown, used = [], 0
    for name in PRIORITY:
        need = WIDTHS[name] + SEP
        if used + need + NOTE_MIN > width:
            break
        shown.append(name)
        used += need
    out = [(COLUMNS.index(c), WIDTHS[c]) for c in COLUMNS if c in shown]
    return [*out, (COLUMNS.index("note"), max(0, width - used))]


def fit(text: str, width: int) -> str:
    return text if len(text) <= width else text[: max(0, width - 1)] + "…"


def fit_topic(words: str, width: int) -> str:
    """A topic's health words at ``width``: the name shortened from its start, never its verdict
    (``…/camera/image_raw ok``, not ``/lab_w0_000/camera/imag…``, which reads like a problem)."""
    if len(words) <= width:
        return words
    name, _, verdict = words.partition(" ")
    room = width - len(verdict) - 2  # "…" and the space
    if not verdict or room < 4:
        return fit(words, width)
    return f"…{name[-room:]} {verdict}"


def line(row: Row, cols: list[tuple[int, int]], selected: bool, stop: StopNote | None = None) -> Text:
    """One row at the columns ``layout`` gave; ``stop``: what the robot answered a stop, in its note."""
    values = cells(row)
    shown = {i for i, _ in cols}
    note = values[-1] if stop is None else stop.words
    if not note and COLUMNS.index("worst topic") not in shown and row.worst_topic:
        note = row.worst_topic  # no room for its column: the note says it
    text = Text(no_wrap=True, overflow="crop")
    for i, w in cols:
        value = note if COLUMNS[i] == "note" else values[i]
        style = ""
        if COLUMNS[i] == "state":
            style = STATE_STYLES.get(row.state, "")
        elif row.figures_at is not None and COLUMNS[i] in LAST_FIGURES:
            style = "dim"  # its last figures, not current ones
        elif COLUMNS[i] == "note" and stop is not None:
            style = "bold red" if stop.failed else "bold"
        elif COLUMNS[i] == "note" and (row.bad is not None or row.flooding is not None):
            style = "bold magenta"
        elif COLUMNS[i] == "note" and row.figures_at is not None:
            style = "dim"
        elif COLUMNS[i] in ("worst topic", "note") and row.worst_health in ("missing", "below", "silent"):
            style = "yellow"
        topic = COLUMNS[i] == "worst topic" or (COLUMNS[i] == "note" and value == row.worst_topic)
        shown_value = fit_topic(value, w) if topic else fit(value, w)
        text.append(shown_value.ljust(w) if COLUMNS[i] != "note" else shown_value, style)
        if COLUMNS[i] != "note":
            text.append(" " * SEP)
    if selected:
        text.stylize("reverse")
    return text


def fit_lines(lines: list[str], width: int) -> list[str]:
    """Each line in ``width`` columns (0: as it is): broken between its parts (``PARTS``), a part still
    too wide between its words, each row after a line's first indented (at 80 columns the head's
    "connecting: client of ..." and the detail's lines were cut)."""
    room = width - len(GO_ON)
    if room <= 0:
        return lines
    out: list[str] = []
    for line in lines:
        if cell_len(line) <= width:
            out.append(line)
            continue
        sep = next((s for s in PARTS if s in line), " ")
        rows: list[str] = []
        for row in fit_fields([line.split(sep)], room, sep):
            rows += fit_fields([row.split(" ")], room) if cell_len(row) > room else [row]
        out += [rows[0], *(GO_ON + r for r in rows[1:])]
    return out




def worse_above(rows: tuple[Row, ...], top: int) -> str:
    """``▲ 3 worse above (2 lost, 1 stale) · Home: the worst first``, or "" when no row above ``top`` is in
    trouble."""
    counts: dict[str, int] = {}
    for r in rows[:top]:
        if r.severity > OK:
            bad = "flooding" if r.flooding is not None else "bad data"
            what = bad if r.severity == BAD else r.state if r.severity >= STALE else "warning"
            counts[what] = counts.get(what, 0) + 1
    if not counts:
        return ""
    which = ", ".join(f"{n} {what}" for what, n in counts.items())
    return f"▲ {sum(counts.values())} worse above ({which}) · Home: the worst first"


class FleetList(Widget, can_focus=True):
    """The rows, the worst first; the selected one highlighted. Drawn line by line, only what fits, and
    only the lines whose text changed are drawn again (a robot's new figures repaint its row alone)."""

    DEFAULT_CSS = "FleetList { height: 1fr; }"
    BINDINGS = [
        Binding("space", "screen.stop", "Stop robot"),  # first in the footer: the key that matters most
        Binding("up", "move(-1)", "Up", show=False),
        Binding("down", "move(1)", "Down", show=False),
        Binding("pageup", "move(-10)", "Page up", show=False),
        Binding("pagedown", "move(10)", "Page down", show=False),
        Binding("home", "top", "Worst first", show=False),  # the "worse above" line names it
        Binding("end", "move(100000)", "Last", show=False),
        Binding("enter", "open", "Open console"),
    ]
    # a new view repaints only when a row's text or style changed (``watch_view``): the views come twice
    # a second, each with its own clock, and the ages shown change once a second at most
    view: reactive[FleetView] = reactive(FleetView, repaint=False)
    selected: reactive[str | None] = reactive(None, repaint=False)
    _shown: tuple[object, ...] | None = None

    def __init__(self, id: str | None = None) -> None:  # Textual's name for it
        super().__init__(id=id)
        self.stops: dict[str, StopNote] = {}  # robot -> what it answered its last stop (its note)
        self._lines: list[Text] = []  # what each line shows
        self._selected_at: tuple[int, str] | None = None  # (line, robot) of the selection

    def set_stops(self, notes: dict[str, StopNote]) -> None:
        """Stops' answers in their rows: one repaint for all of them."""
        self.stops.update(notes)
        self._repaint(self.view)
        self.post_message(self.Highlighted(self.current()))

    def stop_target(self) -> str | None:
        """The robot a stop key goes to: the one the person saw selected (the last paint drew it so),
        not one the selection moved to since (a robot going lost sorts first and takes the selection)."""
        if self._drawn is not None:
            return self._drawn
        row = self.current()
        return None if row is None else row.name

    class Chosen(Message):
        """Enter on a row: open its console."""

        def __init__(self, row: Row) -> None:
            super().__init__()
            self.row = row

    class Highlighted(Message):
        def __init__(self, row: Row | None) -> None:
            super().__init__()
            self.row = row

    _top = 0
    _drawn: str | None = None  # the robot drawn selected by the last paint
    follow = True  # the worst rows in sight, the selection on the worst: until the person moves

    def current(self) -> Row | None:
        rows = self.view.rows
        for r in rows:
            if r.name == self.selected:
                return r
        return rows[0] if rows else None

    def watch_view(self, view: FleetView) -> None:
        for name in [n for n, note in self.stops.items() if note.until <= view.now]:
            del self.stops[name]  # its answer said long enough: the row's own note again
        if view.rows and (self.follow or self.selected not in {r.name for r in view.rows}):
            self.follow = True
            self.selected = view.rows[0].name  # the worst robot, until the person moves
        self._repaint(view)
        self.post_message(self.Highlighted(self.current()))

    def _repaint(self, view: FleetView) -> None:
        """A refresh only when what the rows show changed."""
        shown = (view.filter, *((cells(r), r.worst_health, self.stops.get(r.name)) for r in view.rows))
        if shown != self._shown:
            self._shown = shown
            self._redraw()

    def _redraw(self) -> None:
        """The lines again; the ones whose text changed refreshed, no other."""
        new, old = self.compose_lines(), self._lines
        self._lines = new
        width = self.size.width
        for y in range(max(len(new), len(old))):
            if y >= len(new) or y >= len(old) or new[y] != old[y]:
                self.refresh(Region(0, y, width, 1))

    def shown(self) -> list[str]:
        """The lines as drawn, as text."""
        return [t.plain for t in self._lines]

    def on_resize(self) -> None:
        self._lines = self.compose_lines()
        self.refresh()

    def render_line(self, y: int) -> Strip:
        if self._selected_at is not None and self._selected_at[0] == y:
            self._drawn = self._selected_at[1]  # the person can see it selected now
        text = self._lines[y] if y < len(self._lines) else Text()
        width = self.size.width
        strip = Strip(list(text.render(self.app.console))).crop_extend(0, width, None)
        return strip.apply_style(self.rich_style)

    async def _on_key(self, event: events.Key) -> None:
        """A key read with the ones before it (one write: a paste, a laggy link) and handled after one of
        them moved the focus (``/``): it goes where the focus went, not to this list's keys (an Enter
        that opens a console, an ``h``, a ``q`` typed as part of a pattern)."""
        target = self.screen.focused
        if target is not None and target is not self:
            event.stop()
            event.prevent_default()
            target.post_message(events.Key(event.key, event.character))
            return
        if event.key == "slash":  # the filter now: its binding would run after the keys read with it
            event.stop()
            event.prevent_default()
            await self.run_action("screen.filter")
            return
        await super()._on_key(event)

    def watch_selected(self) -> None:
        self._redraw()
        self.post_message(self.Highlighted(self.current()))

    def action_move(self, step: int) -> None:
        """The person moves: the selection stays on that robot as the order changes (until Home, or a
        move back to the first row, follows the worst again)."""
        names = [r.name for r in self.view.rows]
        if not names:
            return
        i = names.index(self.selected) if self.selected in names else 0
        j = max(0, min(len(names) - 1, i + step))
        self.follow = j == 0
        self.selected = names[j]
        self._redraw()

    def action_top(self) -> None:
        """Home: back to the worst robots first, the selection on the worst."""
        self.follow = True
        if self.view.rows:
            self.selected = self.view.rows[0].name
        self._redraw()

    def action_open(self) -> None:
        """Enter: the selected robot's console, if the person has seen it selected (it was drawn so):
        an Enter typed ahead of a move or a filter opens nothing nobody saw."""
        row = self.current()
        if row is None:
            return
        if row.name != self._drawn:
            self.notify(f"the selection moved to {row.name}: Enter again to open it", severity="warning")
            return
        self.post_message(self.Chosen(row))

    def compose_lines(self) -> list[Text]:
        """The lines that fit: the column header, a "worse above" line when the person scrolled past
        robots in trouble, the rows."""
        width, height = self.size.width, max(1, self.size.height)
        head = Text(no_wrap=True, overflow="crop", style="bold")
        cols = layout(width)
        for i, w in cols:
            head.append(fit(COLUMNS[i], w).ljust(w) + (" " * SEP if COLUMNS[i] != "note" else ""))
        rows = self.view.rows
        self._selected_at = None
        if not rows:
            what = f"no robot matches {self.view.filter!r}" if self.view.filter else "no robot announced yet"
            return [head, Text(what, style="dim")]
        names = [r.name for r in rows]
        i = names.index(self.selected) if self.selected in names else 0
        room = height - 1
        if self.follow:
            self._top = 0
        else:  # the selection kept in sight; a line says what is worse above it
            self._top = min(max(self._top, i - room + 1), i, max(0, len(rows) - room))
            if worse_above(rows, self._top):
                room -= 1
                self._top = min(max(self._top, i - room + 1), i, max(0, len(rows) - room))
        out = [head]
        above = worse_above(rows, self._top)
        if above:
            out.append(Text(above, style="bold reverse red", no_wrap=True, overflow="crop"))
        self._selected_at = (len(out) + i - self._top, rows[i].name)
        out += [
            line(r, cols, r.name == self.selected, self.stops.get(r.name))
            for r in rows[self._top : self._top + room]
        ]
        return out


class FleetScreen(Screen[None]):
    BINDINGS = [
        # from the filter too, where the footer names it (space is text there): as the console's (TYPING)
        Binding("ctrl+k", "stop('typing')", "Stop robot", key_display="^k", priority=True),
        Binding("ctrl+k", "stop", "Stop robot", show=False, priority=True),
        Binding("slash", "filter", "Filter"),
        Binding("S", "stop_shown", "Stop all shown"),
        Binding("h", "history", "History"),
        Binding("escape", "clear", "Clear filter"),
        Binding("q", "app.quit", "Quit"),
        Binding("ctrl+q", "app.quit", "Quit", show=False, priority=True),
    ]
    # the screen draws nothing itself (its widgets do): a new view must not repaint the whole screen (a
    # full update, twice a second, was most of the console's CPU at 200 robots)
    view: reactive[FleetView] = reactive(FleetView, repaint=False)
    pattern: reactive[str] = reactive("", repaint=False)
    history_line: reactive[str] = reactive("", repaint=False)

    def __init__(self, pattern: str = "") -> None:
        super().__init__()
        self.set_reactive(FleetScreen.pattern, pattern)
        self._texts: dict[str, str] = {}
        self._confirm_until = 0.0  # "stop all shown" armed until (monotonic s)
        self._lost: set[str] | None = None  # the robots lost at the last view (None: no view yet)
        self._answers: list[tuple[str, StopNote]] = []  # stops answered, not yet shown (any thread)
        self._answers_lock = threading.Lock()

    def compose(self) -> ComposeResult:
        yield Static(id="fleet-head")
        yield Input(self.pattern, placeholder="filter by name glob (/)", id="fleet-filter")
        yield FleetList(id="fleet-list").data_bind(FleetScreen.view)
        yield Static(id="fleet-detail")
        yield Footer()

    def on_mount(self) -> None:
        self.sample()
        self.set_interval(REFRESH_S, self.sample)
        self.query_one(FleetList).focus()

    @property
    def fleet_app(self) -> FleetApp:
        assert isinstance(self.app, FleetApp)
        return self.app

    def sample(self) -> None:
        self.view = self.fleet_app.source(self.pattern)

    def watch_view(self, view: FleetView) -> None:
        counts = dict(view.counts)
        parts = [f"{counts.get(s, 0)} {s}" for s in ("alive", "stale", "lost")]
        if counts.get("unknown"):
            parts.append(f"{counts['unknown']} unknown")
        if counts.get("bad"):
            parts.append(f"{counts['bad']} bad data")
        shown = f"{len(view.rows)} of {view.total}" if view.filter else f"{view.total}"
        head = f"fleet · {view.session} · {shown} robots: {', '.join(parts)}"  # its own link first
        if view.ignored:
            head += f" · {view.ignored} more names ignored"
        dropped = [f"{view.unknown} odd keys"] if view.unknown else []
        dropped += [f"{view.flood_dropped} over rate"] if view.flood_dropped else []
        if dropped:
            head += f" · dropped {', '.join(dropped)}"
        self._show("#fleet-head", f"{head}\n{problem_line(view)}")
        self._announce_lost(view)

    def _announce_lost(self, view: FleetView) -> None:
        """A robot going lost, said once (with the terminal's bell under ``--bell``)."""
        lost = set(view.names("lost"))
        if self._lost is None:  # the first robots heard of: those already lost are not news
            if view.total:
                self._lost = lost
            return
        if new := sorted(lost - self._lost):
            names = ", ".join(new[:5]) + (f" and {len(new) - 5} more" if len(new) > 5 else "")
            self.notify(f"{clock_time(view.now)} lost: {names}", severity="error", timeout=10)
            if self.fleet_app.bell_on_lost:
                self.app.bell()
        # a robot lost before this console's link went down is not news again when it is back
        self._lost = lost | (self._lost & set(view.names("unknown")))

    def _show(self, selector: str, text: str) -> None:
        """A Static's new text, each line broken to fit its width (``fit_lines``: at 80 columns the head
        and the detail were cut); nothing when it is the text shown at this width. A layout only when
        the number of lines changes: a layout renders the whole screen again (with an age in the detail
        pane, once a second, it was most of the screen's cost at 200 robots)."""
        static = self.query_one(selector, Static)
        fitted = "\n".join(fit_lines(text.splitlines(), static.content_size.width))
        was = self._texts.get(selector)
        if was != fitted:
            self._texts[selector] = fitted
            grew = was is None or was.count("\n") != fitted.count("\n")
            static.update(Text(fitted, no_wrap=True, overflow="ellipsis"), layout=grew)

    def on_resize(self) -> None:
        """Another width: the head and the detail fitted to it again."""
        self.call_after_refresh(self._refit)

    def _refit(self) -> None:
        self.watch_view(self.view)
        self.show_detail(FleetList.Highlighted(self.query_one(FleetList).current()))

    @on(FleetList.Highlighted)
    def show_detail(self, event: FleetList.Highlighted) -> None:
        row = event.row
        lines = [] if row is None else detail_lines(row, self.view.now)
        stopped = None if row is None else self.query_one(FleetList).stops.get(row.name)
        if stopped is not None:
            lines.append(f"stop: {stopped.words}")
        if row is not None and self.history_line.startswith(f"{row.name}: "):
            lines.append(self.history_line.removeprefix(f"{row.name}: "))
        self._show("#fleet-detail", "\n".join(lines))

    def watch_history_line(self) -> None:
        self.show_detail(FleetList.Highlighted(self.query_one(FleetList).current()))

    @on(Input.Changed, "#fleet-filter")
    def filter_changed(self, event: Input.Changed) -> None:
        self.pattern = event.value.strip()
        self.sample()

    # focus moves at once (``set_focus``), not after the keys already read (``focus()`` waits for them):
    # what is typed after ``/`` in one write (a paste, a laggy link, a throttled Pi) goes to the filter
    @on(Input.Submitted, "#fleet-filter")
    def filter_done(self) -> None:
        self.set_focus(self.query_one(FleetList))

    def action_filter(self) -> None:
        self.set_focus(self.query_one("#fleet-filter", Input))

    def action_clear(self) -> None:
        self.query_one("#fleet-filter", Input).value = ""
        self.set_focus(self.query_one(FleetList))

    def action_history(self) -> None:
        row = self.query_one(FleetList).current()
        if row is not None and self.fleet_app.history is not None:
            self.history_line = f"{row.name}: history: asking..."
            self.ask_history(row.name)

    @work(thread=True, exclusive=True)
    def ask_history(self, name: str) -> None:
        assert self.fleet_app.history is not None
        words = history_words(self.fleet_app.history(name, fleet.HISTORY_MINUTES))
        self.app.call_from_thread(setattr, self, "history_line", f"{name}: {words}")

    # -- the stop --------------------------------------------------------------------------------
    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """ctrl+k's shown binding only while the filter has the focus (elsewhere the list shows space)."""
        if action != "stop" or not parameters:
            return True
        return isinstance(self.focused, Input) == (parameters == ("typing",))

    def action_stop(self, _where: str = "") -> None:
        """The robot the person saw selected asked to stop; its row says what it answered."""
        name = self.query_one(FleetList).stop_target()
        if name is None:
            return
        if self.fleet_app.stopper is None:
            self.notify("this fleet view cannot stop robots", severity="warning")
            return
        self.ask_stops([name])

    def action_stop_shown(self) -> None:
        """Every robot the filter shows asked to stop, on a second press within CONFIRM_S."""
        names = [r.name for r in self.view.rows if r.state not in ("lost", "unknown")]
        if self.fleet_app.stopper is None or not names:
            self.notify("no robot here to stop", severity="warning")
            return
        now = time.monotonic()
        if now > self._confirm_until:
            self._confirm_until = now + CONFIRM_S
            which = f" matching {self.view.filter!r}" if self.view.filter else ""
            self.notify(f"press S again within {CONFIRM_S:g} s to stop the {len(names)} robots shown{which}")
            return
        self._confirm_until = 0.0
        self.ask_stops(names)

    def ask_stops(self, names: list[str]) -> None:
        until = self.view.now + STOP_NOTE_S
        asking = StopNote(stop_words("asking it to stop...", time.time()), False, until)
        self.query_one(FleetList).set_stops(dict.fromkeys(names, asking))
        self._stop_many(names)

    class StopsAnswered(Message):
        """Answers are waiting in ``_answers`` (posted from the stop's threads)."""

    @work(thread=True, group="stop", exit_on_error=False)
    def _stop_many(self, names: list[str]) -> None:
        """Each robot asked on a pool's thread; their answers shown in batches (one repaint for the
        answers that came meanwhile, not one per robot), and one line said for all that failed."""
        stop = self.fleet_app.stopper
        assert stop is not None
        failed: list[str] = []
        asked = time.time()

        def one(name: str) -> None:
            at = time.time()
            try:
                answer = stop(name)
                bad = isinstance(answer, str) or not answer.sure
            except Exception as exc:  # a stopper that fails says so in its row; the app goes on
                answer, bad = f"not stopped: asking failed: {exc!r}", True
            note = StopNote(stop_words(answer, at), bad, self.view.now + STOP_NOTE_S)
            with self._answers_lock:
                self._answers.append((name, note))
                first = len(self._answers) == 1
                if isinstance(answer, str):
                    failed.append(answer)
            if first:
                self.post_message(self.StopsAnswered())

        with ThreadPoolExecutor(min(STOPS_AT_ONCE, len(names)), thread_name_prefix="fleet-stop") as pool:
            list(pool.map(one, names))
        if failed:
            line = failed[0] if len(names) == 1 else f"{len(failed)} of {len(names)} robots {failed[0]}"
            more = f" (and {len(set(failed)) - 1} other reasons)" if len(set(failed)) > 1 else ""
            self.app.call_from_thread(self.notify, stop_words(line + more, asked), severity="error")

    @on(StopsAnswered)
    def _stopped(self) -> None:
        with self._answers_lock:
            answers, self._answers = self._answers, []
        if answers:
            self.query_one(FleetList).set_stops(dict(answers))

    @on(FleetList.Chosen)
    def open_console(self, event: FleetList.Chosen) -> None:
        self.fleet_app.open_robot(event.row)


class FleetApp(App[None]):
    CSS_PATH = "fleet.tcss"
    TITLE = "arbiter fleet"

    def __init__(
        self,
        source: Callable[[str], FleetView],
        opener: Callable[[list[str]], int],
        history: Callable[[str, float], fleet.History | str] | None = None,
        pattern: str = "",
        stop: Callable[[str], fleet.StopAnswer | str] | None = None,
        bell_on_lost: bool = False,
        token_file: str | None = None,
        ca_file: str | None = None,
    ) -> None:
        super().__init__()
        self.source, self.opener, self.history, self.stopper = source, opener, history, stop
        self.bell_on_lost = bell_on_lost
        self.pattern, self.token_file, self.ca_file = pattern, token_file, ca_file
        self.opened: list[list[str]] = []  # the consoles opened, in order (what a test reads)

    def get_driver_class(self) -> type[Driver]:
        return fewer_bytes(super().get_driver_class())  # the same picture in fewer bytes (``terminal``)

    def on_mount(self) -> None:
        self.push_screen(FleetScreen(self.pattern))

    def open_robot(self, row: Row) -> None:
        """The single-robot console on ``row``'s advertised URLs, in this terminal; back here when it
        quits. A row that cannot be opened says why."""
        argv = console_argv(row, self.token_file, self.ca_file)
        if isinstance(argv, str):
            self.notify(argv, severity="warning")
            return
        self.opened.append(argv)
        try:
            with self.suspend():
                code = self.opener(argv)
        except SuspendNotSupported:  # no terminal to hand over (a test's headless driver)
            code = self.opener(argv)
        self.notify(f"back from {row.name}" + (f" (exit {code})" if code else ""))
        self.refresh(layout=True)
