"""One marker and colour per controller, on every plot: the terminal's (trajectory, error vs latency)
and the files ``compare --plot`` writes. None is shared with the mission's waypoints, its goal or the
robot, and a name the registry does not know (an observed label, an old export's) gets a style chosen
from its name, so it is the same on every plot and in every session.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

from arbiter_core.controllers import MANUAL


@dataclass(frozen=True, slots=True)
class SeriesStyle:
    marker: str  # one terminal cell
    colour: str  # a Rich colour
    mpl_marker: str  # matplotlib's marker code
    mpl_colour: str  # a matplotlib colour


CONTROLLER_STYLES: dict[str, SeriesStyle] = {
    MANUAL: SeriesStyle("·", "bright_white", ".", "tab:gray"),
    "go_to_goal": SeriesStyle("+", "cyan", "P", "tab:cyan"),
    "pure_pursuit": SeriesStyle("x", "magenta", "X", "tab:purple"),
    "stanley": SeriesStyle("*", "green", "*", "tab:green"),
    "regulated_pure_pursuit": SeriesStyle("#", "bright_blue", "s", "tab:blue"),
    "kanayama": SeriesStyle("%", "dark_orange", "D", "tab:orange"),
}
# what the plots draw besides the controllers' series: never a controller's marker
WAYPOINT = SeriesStyle("o", "yellow", "o", "gold")
GOAL = SeriesStyle("G", "bold red", "$G$", "tab:red")
ROBOT_ARROWS = "→↗↑↖←↙↓↘"  # the robot on the map along its heading: east, then counter-clockwise
# for names the registry does not know, picked by the name's CRC-32: stable across plots and runs
OTHER_STYLES = (
    SeriesStyle("@", "bright_cyan", "^", "tab:brown"),
    SeriesStyle("&", "bright_magenta", "v", "tab:pink"),
    SeriesStyle("$", "bright_green", "<", "tab:olive"),
    SeriesStyle("=", "white", ">", "black"),
)
_RESERVED = {WAYPOINT.marker, GOAL.marker, *ROBOT_ARROWS}
_SERIES = (*CONTROLLER_STYLES.values(), *OTHER_STYLES)
assert len({s.marker for s in _SERIES} | _RESERVED) == len(_SERIES) + len(_RESERVED), (
    "every series its own terminal marker, none a waypoint's, goal's or the robot's"
)
assert len({s.mpl_marker for s in _SERIES}) == len(_SERIES), "every series its own matplotlib marker"


def style_of(name: str) -> SeriesStyle:
    """The style of controller ``name``: its own, or one picked from its name (never by position)."""
    known = CONTROLLER_STYLES.get(name)
    if known is not None:
        return known
    return OTHER_STYLES[zlib.crc32(name.encode("utf-8")) % len(OTHER_STYLES)]
