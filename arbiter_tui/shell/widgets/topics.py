"""The topics screen's widgets (the table also on the dashboard): the topics list, its pane on the
dashboard, the selected topic's figures, its rate over the last minute, and the filter."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from rich.cells import cell_len
from rich.text import Text
from textual import events
from textual.binding import Binding
from textual.reactive import reactive
from textual.widget import Widget
from textual.widgets import Input
from textual_plot import HiResMode

from arbiter_core.topicstats import SAMPLE_S, TopicFigures

from ...analytics import axes
from ...latency.topics_client import TopicsState
from ...latency.topics_table import (
    COLUMNS,
    aligned,
    cells,
    detail,
    headers,
    select,
    short_type,
)
from ...session.frames import Frame
from ...session.views import PLOT_PERIOD_S
from .plots import MIN_GAP_X, MIN_GAP_Y, Plot

# column -> width; columns are shown in PRIORITY order while they fit, the topic column takes the rest
WIDTHS = dict(zip(COLUMNS, (18, 20, 7, 6, 6, 6, 6, 7, 6, 7), strict=True))
PRIORITY = ("topic", "state", "Hz", "age", "B/s", "delay", "pub/sub", "size", "usual", "type")


def layout(width: int) -> tuple[int, ...]:
    """Indices into COLUMNS of the columns shown at ``width``, in COLUMNS order."""
    shown: list[str] = []
    used = 0
    for name in PRIORITY:
        need = WIDTHS[name] + (1 if shown else 0)
        if used + need > width:
            break
        shown.append(name)
        used += need
    return tuple(i for i, c in enumerate(COLUMNS) if c in shown)


def column_widths(width: int, rows: Sequence[TopicFigures]) -> tuple[tuple[int, ...], list[int]]:
    """The columns shown at ``width`` (``layout``) and their widths: the columns free beyond the fixed
    ones go to the topic's name and type, each up to its longest cell in ``rows`` and in proportion to
    what it lacks when both cannot have it; what is left, to the name."""
    shown = layout(width)
    names = [COLUMNS[i] for i in shown]
    widths = [WIDTHS[c] for c in names]
    free = max(0, width - sum(widths) - len(widths) + 1)
    longest = {
        "topic": max((cell_len(t.name) for t in rows), default=0),
        "type": max((cell_len(short_type(t.type)) for t in rows), default=0),
    }
    lack = {c: max(0, longest[c] - WIDTHS[c]) for c in ("topic", "type") if c in names}
    wanted = sum(lack.values())
    for column, short in lack.items():
        widths[names.index(column)] += short if wanted <= free else free * short // wanted
    widths[0] += max(0, width - sum(widths) - len(widths) + 1)  # the rest: the topic column
    return shown, widths


STYLES = {
    "slow": "yellow", "silent": "bold red", "quiet": "dim", "waiting": "dim", "unmeasured": "dim",
    "unknown": "yellow",
}  # fmt: skip


class TopicsList(Widget, can_focus=True):
    """The table: a header and one line per topic, the selected one highlighted. Drawn as text (a
    DataTable refilled at every poll was a third of the latency screen's CPU)."""

    DEFAULT_CSS = "TopicsList { height: 1fr; }"
    BINDINGS = [
        Binding("up", "move(-1)", "Up", show=False),
        Binding("down", "move(1)", "Down", show=False),
        Binding("pageup", "move(-10)", "Page up", show=False),
        Binding("pagedown", "move(10)", "Page down", show=False),
        Binding("home", "move(-100000)", "First", show=False),
        Binding("end", "move(100000)", "Last", show=False),
    ]
    # a new answer repaints only when a cell shown changed (``watch_state``); the rest repaint at once
    state: reactive[TopicsState] = reactive(TopicsState, repaint=False)
    text: reactive[str] = reactive("")
    sort: reactive[str] = reactive("name")
    reverse: reactive[bool] = reactive(False)
    selected: reactive[str | None] = reactive(None)
    renders = 0
    _shown: object = None

    def rows(self) -> list[TopicFigures]:
        return select(self.state.topics, self.text, self.sort, self.reverse)

    def action_move(self, step: int) -> None:
        names = [t.name for t in self.rows()]
        if not names:
            return
        i = names.index(self.selected) if self.selected in names else 0
        self.selected = names[max(0, min(len(names) - 1, i + step))]

    def watch_state(self) -> None:
        rows = self.rows()
        names = [t.name for t in rows]
        if names and self.selected not in names:
            self.selected = names[0]
        shown = (tuple(cells(t) for t in rows), self.state.polls == 0, self.state.error if not rows else None)
        if shown != self._shown:
            self._shown = shown
            self.refresh()

    def render(self) -> Text:
        self.renders += 1
        rows = self.rows()
        shown, widths = column_widths(self.size.width, rows)
        out = Text(no_wrap=True, overflow="ellipsis")
        names_shown = tuple(COLUMNS[i] for i in shown)
        titles = headers(self.sort, self.reverse)  # the sorted column marked ▼ or ▲
        out.append(_line(tuple(titles[i] for i in shown), widths, names_shown) + "\n", style="bold")
        if not rows:
            out.append(self._empty(), style="dim")
            return out
        visible = max(1, self.size.height - 1)
        names = [t.name for t in rows]
        cursor = names.index(self.selected) if self.selected in names else 0
        first = max(0, min(cursor - visible // 2, len(rows) - visible))
        for i, t in enumerate(rows[first : first + visible]):
            style = STYLES.get(t.state, "")
            if first + i == cursor:
                style = f"{style} reverse".strip() if self.has_focus else f"{style} underline".strip()
            row = cells(t)
            out.append(_line(tuple(row[j] for j in shown), widths, names_shown) + "\n", style=style)
        return out

    def _empty(self) -> str:
        s = self.state
        if s.unavailable is not None:
            return s.unavailable
        if s.polls == 0:
            return "waiting for the backend's /api/topics ..."
        if s.error and not s.topics:
            return f"no topics: {s.error}"
        if self.text:
            return f"no topic matches {self.text!r}"
        return "the backend sees no topic"


class TopicsPane(TopicsList, can_focus=False):
    """Screen 4's table on the dashboard: the app's latest answer, sorted by name, never focused (the
    arrow keys drive there)."""

    frame: reactive[Frame] = reactive(Frame, repaint=False)  # bound to the screen's

    def watch_frame(self, frame: Frame) -> None:
        self.state = frame.topics


def _line(values: tuple[str, ...], widths: list[int], columns: tuple[str, ...]) -> str:
    return " ".join(aligned(v, w, c) for v, w, c in zip(values, widths, columns, strict=True))


class TopicDetail(Widget):
    """The selected topic's figures."""

    DEFAULT_CSS = "TopicDetail { height: auto; }"
    state: reactive[TopicsState] = reactive(TopicsState, repaint=False)
    selected: reactive[str | None] = reactive(None)
    _shown: str | None = None

    def watch_state(self) -> None:
        text = self.render().plain
        if text != self._shown:  # an answer that changed nothing this pane shows paints nothing
            self._shown = text
            self.refresh()

    def render(self) -> Text:
        t = next((t for t in self.state.topics if t.name == self.selected), None)
        if t is None:
            return Text("" if self.state.unavailable else "select a topic (up/down)", style="dim")
        lines = detail(t, self.state.window_s)
        out = Text(lines[0] + "\n", style="bold")
        out.append("\n".join(lines[1:]))
        if self.state.error:
            out.append(f"\nlast poll failed: {self.state.error}", style="red")
        elif self.state.interrupted and t.state != "unknown":  # an unknown topic's note says it already
            out.append(f"\n{self.state.interrupted}", style="yellow")
        echo = self.state.echo
        if echo is not None and echo[0] == t.name:
            out.append("\nlatest (at most 2/s): ", style="bold")
            out.append(echo[1], style="dim" if echo[1].startswith(("not echoed", "waiting")) else "")
        return out


@dataclass(frozen=True)
class RatesKey:
    topic: str | None
    rates: tuple[float | None, ...] | None  # None: no rate at all (nothing to redraw)


class RatePlot(Plot[TopicsState, RatesKey]):
    """The selected topic's rate over the last minute, once a second, as the backend sampled it."""

    selected: reactive[str | None] = reactive(None)

    def pick(self, frame: Frame) -> TopicsState:
        return frame.topics

    def watch_selected(self) -> None:
        if self.is_mounted:
            self._key = None
            self._receive(self.pick(self.frame))

    def data_key(self, view: TopicsState) -> RatesKey:
        rates = view.rates(self.selected or "")
        return RatesKey(self.selected, rates if any(r is not None for r in rates) else None)

    def follow_period(self, old: RatesKey | None, new: RatesKey) -> float:
        """The same topic's rates: at most every ``PLOT_PERIOD_S`` (another topic: at once)."""
        return PLOT_PERIOD_S if old is not None and old.topic == new.topic else 0.0

    def draw(self, view: TopicsState) -> None:
        rates = view.rates(self.selected or "")
        values = np.array([np.nan if r is None else r for r in rates], dtype=np.float64)
        if values.size < 2 or np.all(np.isnan(values)):
            return
        t = (np.arange(values.size) - (values.size - 1)) * SAMPLE_S  # seconds before the newest sample
        ok = ~np.isnan(values)
        self.plot(t[ok], values[ok], line_style="cyan", hires_mode=HiResMode.BRAILLE)
        cols, rows = self.scale_size()
        x = axes.aligned(float(t[0]), 0.0, cols, MIN_GAP_X)
        y = axes.aligned(0.0, max(float(np.nanmax(values)) * 1.1, 1.0), rows, MIN_GAP_Y)
        self.set_axes(x, y)


class FilterInput(Input):
    """The filter: it takes keys only once opened (``/`` or a click), so keys typed as the screen opens,
    or any time after, go to the table; ``esc`` and ``enter`` close it (the screen's)."""

    can_focus = False
    # Its editing keys (backspace, arrows, home...) are bindings, which Textual answers once a key has
    # bubbled up to the app: after an enter or esc typed behind them (a burst), which has moved the focus
    # by then, so they were lost. Answered as they reach it, they keep their place among the typed text.
    EDITING = {k: b.action for b in Input.BINDINGS if isinstance(b, Binding) for k in b.key.split(",")}

    async def _on_key(self, event: events.Key) -> None:
        action = self.EDITING.get(event.key)
        if action is None:
            await super()._on_key(event)
            return
        event.stop()
        event.prevent_default()
        await self.run_action(action)

    def open(self) -> None:
        self.can_focus = True
        self.screen.set_focus(self)  # now, not after the keys already queued: they are typed into it

    def close(self) -> None:
        self.can_focus = False

    def on_click(self) -> None:
        self.open()
