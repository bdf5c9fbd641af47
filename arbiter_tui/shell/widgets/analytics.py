"""The analytics screen's widgets (also on the dashboard): the comparison table, the rule it names, the
ring's warning, the recording banner, the empty state and the line that places the measured latency on
the error-vs-latency curve. Each shows its part of the frame (``Bound``) and does no work when it did
not change."""

from __future__ import annotations

from rich.text import Text
from textual import on
from textual.reactive import reactive
from textual.widget import Widget
from textual.widgets import DataTable
from textual.widgets.data_table import ColumnKey

from ...analytics import table as T
from ...analytics.linkcurve import LinkSweepView
from ...session.frames import Frame
from ...session.views import AnalyticsView
from .text import Bound

# The full view where every column fits the width the table has (its columns, their widest cell), else
# the compact one (every number still shown); before it is laid out, as if it had FULL_WIDTH columns
FULL_WIDTH = 104
SCROLLBAR = 2  # a vertical scrollbar's columns, when its rows scroll


def _cell(table: T.Table, row: int, column: int) -> Text:
    text = table.rows[row][column]
    if row in table.group_rows:
        return Text(text, style="bold underline")
    if table.compact and column in table.marked[row]:
        return Text(text, style="bold reverse")  # the best of its column: not by colour alone
    return Text(text, style="bold" if T.BEST_CELL in text or T.BEST_ROW in text else "")


class CompareTable(DataTable[Text]):
    """The comparison: refilled only when its rows, its mode or its order changed. Headers sort. It takes
    focus (tab), so every run can be reached with the arrow keys and page up/down, and columns that do
    not fit scroll sideways with left/right."""

    can_focus = True
    mode: reactive[str] = reactive(T.BY_ALGORITHM)
    room: reactive[int] = reactive(0)  # the columns it is given (0: not laid out yet)
    sort: reactive[str] = reactive(T.RANK)  # type: ignore[assignment]  # hides DataTable.sort, unused here
    descending: reactive[bool] = reactive(False)
    frame: reactive[Frame] = reactive(Frame, repaint=False, init=False)  # bound to the screen's
    fills = 0  # tests: how often the table was rebuilt (a changed cell is updated in place)

    def on_mount(self) -> None:
        self._shown: tuple[object, ...] | None = None
        self.table = T.build(self.mode, (), ())
        self.call_after_refresh(self._refill)  # filled once mounted (the dashboard mounts it late)

    def watch_frame(self, old: Frame, new: Frame) -> None:
        if new.analytics != old.analytics:
            self._refill(new.analytics)

    def watch_mode(self) -> None:
        self._refill()

    def watch_room(self) -> None:
        self._refill()

    def on_resize(self) -> None:
        # the width it is given: the whole screen, or half of the dashboard
        self.room = self.parent.size.width if isinstance(self.parent, Widget) else self.app.size.width

    @property
    def compact(self) -> bool:
        return self.table.compact

    def watch_sort(self) -> None:
        self._refill()

    def watch_descending(self) -> None:
        self._refill()

    def _refill(self, view: AnalyticsView | None = None) -> None:
        if not self.is_mounted:
            return
        view = view or self.frame.analytics
        # built each time (a few rows), shown only when what it prints changed: a run whose samples the
        # ring drops, or one sample more outside every run, changes nothing here
        table = T.build(self.mode, view.runs, view.by_algorithm, self.sort, self.descending)
        if T.width(table) + SCROLLBAR > (self.room or FULL_WIDTH):  # the full view would scroll sideways
            table = T.build(self.mode, view.runs, view.by_algorithm, self.sort, self.descending, compact=True)
        key = (self.sort, self.descending, table)
        if key == self._shown:
            return
        same_shape = self._shown is not None and self._shown[:2] == key[:2] and self.row_count > 0
        self._shown = key
        old, self.table = self.table, table
        for rule in self.screen.query(RuleLine):
            rule.refresh()
        if same_shape and (old.keys, len(old.rows)) == (table.keys, len(table.rows)):
            # same columns, order and row count: change only the cells that differ (cheaper than a refill)
            for i, (before, after) in enumerate(zip(old.rows, table.rows, strict=True)):
                for j, (k, a, b) in enumerate(zip(table.keys, before, after, strict=True)):
                    if a != b or (j in old.marked[i]) != (j in table.marked[i]):
                        cell = _cell(table, i, j)
                        # the columns' widths are worked out again only for a cell wider than its column
                        wider = cell.cell_len > self.columns[ColumnKey(k)].content_width
                        self.update_cell(str(i), k, cell, update_width=wider)
            return
        self.fills += 1
        self.clear(columns=True)
        for header, k in zip(table.headers, table.keys, strict=True):
            arrow = (" ▼" if self.descending else " ▲") if k == self.sort else ""
            self.add_column(Text(header + arrow, style="bold"), key=k)
        for i, row in enumerate(table.rows):
            self.add_row(*(_cell(table, i, j) for j in range(len(row))), key=str(i))

    def sort_by(self, key: str) -> None:
        """Sort by a column; choosing it again reverses the order."""
        if key == self.sort:
            self.descending = not self.descending
        else:
            self.sort, self.descending = key, False

    @on(DataTable.HeaderSelected)
    def _header_clicked(self, event: DataTable.HeaderSelected) -> None:
        self.sort_by(str(event.column_key.value))


class RuleLine(Bound[AnalyticsView]):
    """The rule that names the best, and the best it names."""

    view: reactive[AnalyticsView] = reactive(AnalyticsView)

    def pick(self, frame: Frame) -> AnalyticsView:
        return frame.analytics

    def draw(self) -> Text:
        table = self.screen.query_one(CompareTable).table if self.is_mounted else None
        return Text(T.legend(table) if table else "")


class RingWarning(Bound[AnalyticsView]):
    """Says when the ring buffer has dropped samples of a run: the cards and plots no longer show all of
    it, the run and algorithm rows still do."""

    DEFAULT_CSS = "RingWarning { height: auto; color: $warning; text-style: bold; padding: 0 1; }"
    view: reactive[AnalyticsView] = reactive(AnalyticsView)
    short: reactive[bool] = reactive(False, layout=True)  # a short terminal: its first sentence only

    def pick(self, frame: Frame) -> AnalyticsView:
        return frame.analytics

    def watch_view(self, view: AnalyticsView) -> None:
        self.display = bool(view.dropped_runs)

    def draw(self) -> Text:
        dropped = self.view.dropped_runs
        if not dropped:
            return Text()
        parts = ", ".join(
            f"run {r.id} {'all' if r.in_ring == 0 else r.dropped} of {r.stats.sampleCount}" for r in dropped
        )
        if self.view.source:  # a file: its ring had dropped them when it was written
            why = "" if self.short else " Rows count every sample recorded; cards and plots the file's."
            return Text(f"⚠ the file lacks samples of: {parts}.{why}", no_wrap=False)
        why = "" if self.short else " Rows still count every sample; cards and plots show only the ring."
        return Text(f"⚠ ring buffer ({self.view.ring} points) dropped: {parts}.{why}", no_wrap=False)


class FileBanner(Bound[AnalyticsView]):
    """A recording is shown, not the live session: what file, as what it was graded, and how back."""

    DEFAULT_CSS = "FileBanner { height: auto; padding: 0 1; background: $accent 30%; text-style: bold; }"
    view: reactive[AnalyticsView] = reactive(AnalyticsView)

    def pick(self, frame: Frame) -> AnalyticsView:
        return frame.analytics

    def watch_view(self, view: AnalyticsView) -> None:
        self.display = bool(view.source)

    def draw(self) -> Text:
        v = self.view
        if not v.source:
            return Text()
        runs = f"{len(v.runs)} run{'s' if len(v.runs) != 1 else ''}"
        if v.plans:
            runs += f" ({v.plans} plan{'s' if v.plans != 1 else ''})"
        text = Text(f"FILE {v.source}: {v.points} samples, {runs}, graded as `arbiter-tui stats` grades "
                    "it · esc: the live session", no_wrap=False)  # fmt: skip
        for note in v.notes:
            text.append(f"\nnote: {note}", style="not bold")
        return text


class EmptyState(Bound[AnalyticsView]):
    """Says why there is nothing to show, and what to do: recording is on and nothing moved yet, or it is
    paused."""

    DEFAULT_CSS = "EmptyState { height: auto; padding: 0 1; color: $text-muted; }"
    view: reactive[AnalyticsView] = reactive(AnalyticsView)

    def pick(self, frame: Frame) -> AnalyticsView:
        return frame.analytics

    def watch_view(self, view: AnalyticsView) -> None:
        self.display = view.points == 0 and not view.runs

    def draw(self) -> Text:
        if not self.view.collecting:
            return Text("Recording is paused — press r to record.", style="bold yellow")
        return Text(
            "● Recording. Nothing yet: drive (1, then a movement key) or start a mission (g); "
            "samples appear here. A robot standing still adds none.",
            no_wrap=False,
        )


class LinkLine(Bound[LinkSweepView]):
    """Where the latency this console measures falls on the error-vs-latency curve, in words."""

    DEFAULT_CSS = "LinkLine { height: auto; padding: 0 1; }"
    ROWS = 2  # its max-height in analytics.tcss
    view: reactive[LinkSweepView] = reactive(LinkSweepView)

    def pick(self, frame: Frame) -> LinkSweepView:
        return frame.link_sweep

    def draw(self) -> Text:
        # whole controllers only: the ones that do not fit in two lines are left out, with an ellipsis
        return Text(self.view.text(self.content_size.width, self.ROWS), no_wrap=False)
