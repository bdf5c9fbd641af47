"""The command palette (ctrl+p) and its commands: screens, stop, controllers, missions, go, goal,
collection, clear and export, each the same call its key makes."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from functools import partial
from typing import Any

from textual.app import App, ComposeResult, SystemCommand
from textual.command import CommandPalette
from textual.widgets import Footer

from arbiter_core.controllers import ALGORITHMS, MISSIONS

from ..analytics.files import FORMATS
from .keys import STOP_HINT_TYPING
from .screens.base import Console

SCREENS = ("control", "analytics", "latency", "topics")
PROMPT = "Search for commands…  (ctrl+k stops the robot)"


class StopPalette(CommandPalette):
    """Textual's palette with a footer of its own naming the stop key while one types (``^k``: space
    and k are text here). Without it the screen's footer behind showed that screen's keys, letters that
    are text in the palette."""

    BINDINGS = [STOP_HINT_TYPING]

    def __init__(self) -> None:
        super().__init__(id="--command-palette", placeholder=PROMPT)

    def compose(self) -> ComposeResult:
        yield from super().compose()
        yield Footer(show_command_palette=False, compact=True)


def commands(
    app: App[Any], console: Console, switch: Callable[[str], None], recording_shown: bool = False
) -> Iterable[SystemCommand]:
    """``recording_shown``: screen 2 shows a file, so "Back to the live session" is offered."""
    session = console.session

    def then_show(action: Callable[[], object]) -> Callable[[], None]:
        def run() -> None:
            action()
            console.refresh_frame(force=True)

        return run

    for name in SCREENS:
        yield SystemCommand(f"Screen: {name}", f"Switch to the {name} screen", lambda n=name: switch(n))
    yield SystemCommand(
        "Stop the robot",
        "Whatever drives it (space, k or ctrl+k)",
        then_show(lambda: session.stop_all("palette")),
    )
    for algo in ALGORITHMS:
        yield SystemCommand(
            f"Algorithm: {algo}",
            "Select the controller (g runs it)",
            then_show(partial(session.select_algorithm, algo)),
        )
    for mission in MISSIONS:
        yield SystemCommand(
            f"Mission: {mission}",
            "Select the mission (g runs it)",
            then_show(partial(session.select_mission, mission)),
        )
    yield SystemCommand(
        "Go", "Resume the interrupted mission, or start the selected one (g)", lambda: console.go()
    )
    yield SystemCommand(
        "Restart the mission", "From its first waypoint (G)", lambda: console.go(restart=True)
    )
    yield SystemCommand(
        "Set a goal x y…", "Type a go-to-goal target in metres (t)", console.dialogs.ask_goal
    )
    yield SystemCommand(
        "Start/pause collection", "Toggle analytics collection", then_show(session.toggle_collection)
    )
    yield SystemCommand("Clear collected data", "Asks first", console.dialogs.ask_clear)
    yield SystemCommand(
        "Open a recording…", "A ros2 bag or an export, graded as `stats` grades it (f on screen 2)",
        console.dialogs.open_recording,
    )  # fmt: skip
    if recording_shown:
        yield SystemCommand(
            "Back to the live session", "Leave the recording shown on screen 2 (escape there)",
            console.dialogs.live_session,
        )  # fmt: skip
    for fmt in FORMATS:
        yield SystemCommand(
            f"Export {fmt.upper()}",
            f"Write the collected data as {fmt}",
            lambda f=fmt: console.dialogs.export(f),
        )
