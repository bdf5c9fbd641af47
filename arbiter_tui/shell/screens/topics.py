"""Topics screen: is every topic on the robot alive? Rate, bandwidth, delay and age of each, measured by the
backend (``GET /api/topics``), filterable and sortable, with the selected topic's figures and its rate
over the last minute."""

from __future__ import annotations

from textual import events, on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.reactive import reactive
from textual.widgets import Input

from ...latency.topics_client import TopicsState
from ...latency.topics_table import (
    SORT_ORDER,
)
from ...session.frames import Frame
from ..widgets.topics import FilterInput, RatePlot, TopicDetail, TopicsList
from .base import BaseScreen


class TopicsScreen(BaseScreen):
    CSS_PATH = ["base.tcss", "topics.tcss"]
    AUTO_FOCUS = "#topics-list"  # never the filter: a key typed as the screen first opens is the table's
    BINDINGS = [
        # priority: answered as they come, before the keys typed after them are handed on (a burst such
        # as "/odom" or "odom<esc>s" lands where it was meant); check_action passes them on otherwise
        Binding("slash", "filter", "Filter", priority=True),
        Binding("slash", "filter", "Filter", show=False),  # a / typed while the screen was still opening
        Binding("escape,enter", "table", "Table", show=False, priority=True),
        Binding("s", "sort", "Sort"),
        Binding("r", "reverse", "Flip", tooltip="Reverse the order of the sorted column"),
    ]
    # data for the widgets bound to them: a change repaints those widgets, never the whole screen
    state: reactive[TopicsState] = reactive(TopicsState, repaint=False)
    selected: reactive[str | None] = reactive(None, repaint=False)
    sort: reactive[str] = reactive("name", repaint=False)

    def compose_body(self) -> ComposeResult:
        hint = "/ filters by name or type; esc: the table; ctrl+k stops the robot"  # fits 80 columns
        yield FilterInput(placeholder=hint, id="topics-filter")
        yield TopicsList(id="topics-list").data_bind(TopicsScreen.state, TopicsScreen.sort)
        with Horizontal(id="topics-side"):
            yield TopicDetail(id="topics-detail").data_bind(TopicsScreen.state, TopicsScreen.selected)
            yield RatePlot("rate (Hz) vs time (s)", id="topics-rate").data_bind(
                BaseScreen.frame, BaseScreen.plot_budget, TopicsScreen.selected
            )

    def watch_frame(self, frame: Frame) -> None:
        self.state = frame.topics

    def on_mount(self) -> None:
        # (BaseScreen's on_mount runs too: Textual calls the handler of every class in the MRO)
        self.watch(self.query_one(TopicsList), "selected", self._select, init=True)

    def _select(self, name: str | None) -> None:
        if name != self.selected:
            self.selected = name
            self._echo(name)

    def _echo(self, name: str | None) -> None:
        """Echo ``name``'s latest message (None: stop), through the link's own subscription."""
        figures = next((t for t in self.state.topics if t.name == name), None)
        self.console.session.echo_topic(figures)  # shown with the next topics answer (at most 0.5 s)

    def on_screen_suspend(self) -> None:
        self._echo(None)  # nobody looks at it: unsubscribe

    def on_screen_resume(self) -> None:
        # (BaseScreen's runs too, once: no super() call, which ran it twice and forced two frames)
        self.console.keys.set_direct(False)  # this screen's keys are typed: no teleop here
        self._echo(self.selected)

    @on(Input.Changed, "#topics-filter")
    def _filtered(self, event: Input.Changed) -> None:
        self.query_one(TopicsList).text = event.value

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """``/`` opens the filter, and is text in it; ``esc`` and ``enter`` leave it (elsewhere: theirs)."""
        if action == "filter":
            return not isinstance(self.focused, FilterInput)
        if action == "table":
            return isinstance(self.focused, FilterInput)
        return True

    def action_table(self) -> None:
        self.query_one(FilterInput).close()
        self.set_focus(self.query_one(TopicsList))  # now: the keys queued behind this one are the table's

    @on(events.DescendantFocus)
    def _focused(self, event: events.DescendantFocus) -> None:
        if not isinstance(event.widget, FilterInput):  # a click on the table: the filter closes too
            self.query_one(FilterInput).close()

    def action_filter(self) -> None:
        self.query_one(FilterInput).open()

    def action_sort(self) -> None:
        self.sort = SORT_ORDER[(SORT_ORDER.index(self.sort) + 1) % len(SORT_ORDER)]
        self.notify(f"sorted by {self.sort}", timeout=1.5)

    def action_reverse(self) -> None:
        lst = self.query_one(TopicsList)
        lst.reverse = not lst.reverse
