"""The help screen (``?``)."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import VerticalScroll
from textual.screen import ModalScreen
from textual.widgets import Footer, Static

from ...control.teleop import legend_long
from ..keys import STOP_HINT

HELP = f"""[b]arbiter-tui[/b] — teleop console, analytics and latency monitor

[b]Screens[/b]  1 control  2 analytics  3 latency  4 topics  ? help  ctrl+p
[b]Stop[/b]     ctrl+k anywhere, whatever drives; space or k where not text
         (text: the goal prompt, the filter, the palette, a recording's path)
[b]Quit[/b]     ctrl+q or ctrl+c (robot stopped first)   R: a lost session's journal

[b]Control[/b] (teleop_twist_keyboard keys; hold a key to keep moving)
{legend_long()}
  a algorithm (manual and five controllers)  n mission
  g go (resumes an interrupted mission)  G restart the mission
  t type a goal x y   click the map: drive there
  Map: o waypoints and G goal where g takes the robot; * is stale.
  A held key ends on leaving this screen; a mission keeps driving.
  Focus loss or a too-small window stops the robot.
  At 160x45 and more this screen is the dashboard.

[b]Analytics[/b]  r record/pause  v per algorithm / per run  s sort
  ctrl+s export  delete clear (asks)  f open a recording (esc: live)
  ranked per mission, overall over missions every algorithm completed
[b]Latency[/b]  GET /api/latency at 2 Hz; one-way = receive - stamp

[b]Topics[/b]  / filter (esc, enter: back)  s sort (name, rate, bandwidth,
  delay, age)  r reverse (flip)  the header marks the sorted column ▼ ▲
  up/down select; rate, bandwidth, delay, age of every topic as
  the backend measures it (GET /api/topics, 2 Hz)"""


class HelpScreen(ModalScreen[None]):
    # One scrollbar, where a scrollbar is: against the dialog's frame, the whole height inside it, and a
    # frame drawn as a line. (A thick frame is a solid bar on each side, and the scrollbar floated inside
    # the padding beside it: two bars on the right, read as two thumbs.)
    DEFAULT_CSS = """
    HelpScreen { align: center middle; }
    HelpScreen > VerticalScroll {
        width: 78; height: auto; max-height: 100%; border: round $primary; background: $surface;
    }
    HelpScreen > VerticalScroll > Static { padding: 1 2; }
    """
    BINDINGS = [Binding("escape,question_mark,q", "dismiss", "Close"), STOP_HINT]

    def compose(self) -> ComposeResult:
        with VerticalScroll():
            yield Static(HELP)
        yield Footer(show_command_palette=False, compact=True)
