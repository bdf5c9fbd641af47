"""The plots' canvases repaint only the rows whose cells changed.

textual-plot clears and redraws a plot's canvases whenever its data changes (the map at every frame
while the robot moves, the analytics plots once a second), and ``textual_hires_canvas.Canvas``
refreshes the whole widget on every change. Textual then asks for every row again, and
``Canvas.render_line`` walks each cell of the row in Python to build its strip. Most rows come out as
they were: the map's grid and the trail behind the robot, the axes' tick labels, the empty part of
every plot. On the control screen with a held key that walk was a third of all painting (py-spy,
docs/BENCHMARKS.md, session 17).

:func:`install` keeps, per canvas and row, the strip last built and the row's content it was built from
(its characters and their styles, each joined into one string, which Python does at C speed, and the
widget's base style); a row whose content is the same gets that same strip back. The base style
(``rich_style``, which walks the widget's ancestors: most of what the library's ``render_line`` cost)
is worked out once per paint of the canvas, not once per row. Any change, whatever
drew it, changes the key, so the strip is built again by the library's own code: nothing is ever shown
stale. Applied only to the textual-hires-canvas release it was checked against (``CHECKED``); another
release keeps its own code.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from typing import Any

from textual.geometry import Region
from textual.strip import Strip
from textual_hires_canvas.canvas import Canvas

CHECKED = ("0.14.0",)
SEP = "\x00"  # between styles: no style string holds it

_render_line = Canvas.render_line
_render_lines = Canvas.render_lines


def _render_lines_once(self: Canvas, crop: Region) -> list[Strip]:
    """One paint of the canvas: its base style looked up once for all its rows."""
    self.__dict__["_arbiter_base"] = self.rich_style
    try:
        return _render_lines(self, crop)
    finally:
        self.__dict__.pop("_arbiter_base", None)


def _render_line_cached(self: Canvas, y: int) -> Strip:
    size = self._canvas_size
    if not size.area or y >= size.height:
        return _render_line(self, y)
    base = self.__dict__.get("_arbiter_base")
    if base is None:  # asked for one row outside a paint
        base = self.rich_style
    key = (base, "".join(self._buffer[y]), SEP.join(self._styles[y]))
    rows: dict[int, tuple[Any, Strip]] | None = self.__dict__.get("_arbiter_rows")
    if rows is None:
        rows = self.__dict__["_arbiter_rows"] = {}
    kept = rows.get(y)
    if kept is not None and kept[0] == key:
        return kept[1]
    strip = _render_line(self, y)
    rows[y] = (key, strip)
    return strip


def install() -> bool:
    """Patch ``Canvas.render_line`` (once; idempotent). False when this release was not checked."""
    try:
        release = version("textual-hires-canvas")
    except PackageNotFoundError:
        return False
    if release not in CHECKED:
        return False
    Canvas.render_line = _render_line_cached  # type: ignore[method-assign]
    Canvas.render_lines = _render_lines_once  # type: ignore[method-assign]
    return True
