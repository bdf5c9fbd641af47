"""The plots' canvases repaint only the rows whose cells changed.

textual-plot clears and redraws a plot's canvases whenever its data changes (the map at every frame
while the robot moves, the analytics plots once a second), and ``textual_hires_canvas.Canvas``
refreshes the whole widget on every change. Textual then styles, filters and composes every row again,
and ``Canvas.render_line`` walks each cell of each row in Python to build its strip. Most rows come
out as they were: the map's grid and the trail behind the robot, the axes' tick labels, the empty part
of every plot. On the control screen with a held key that walk was a third of all painting (py-spy,
docs/BENCHMARKS.md, session 17).

* :func:`changed_rows_only` wraps a redraw: the canvases' refreshes are held (the library's own
  batching counter) and then each canvas is refreshed on the rows whose content differs from what was
  painted, so Textual paints those rows only.
* :func:`install` keeps, per canvas and row, the strip last built and the row's content it was built
  from (its characters and their styles, each joined into one string, which Python does at C speed,
  and the widget's base style); a row whose content is the same gets that same strip back. The base
  style (``rich_style``, which walks the widget's ancestors: most of what the library's
  ``render_line`` cost) is worked out once per paint of the canvas, not once per row.

Any change, whatever drew it, changes a row's content, so the row is refreshed and its strip built
again by the library's own code: nothing is shown stale (``tests/unit/test_canvas_rows.py`` reads the
screen back). Applied only to the textual-hires-canvas release it was checked against (``CHECKED``);
another release keeps its own code and whole refreshes.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from importlib.metadata import PackageNotFoundError, version
from typing import Any

from textual.geometry import Region
from textual.strip import Strip
from textual.widget import Widget
from textual_hires_canvas.canvas import Canvas

from . import give_way

CHECKED = ("0.14.0",)
SEP = "\x00"  # between styles: no style string holds it

_render_line = Canvas.render_line
_render_lines = Canvas.render_lines
_installed = False


def _render_lines_once(self: Widget, crop: Region) -> list[Strip]:
    """One paint of the canvas: its base style looked up once for all its rows (after giving way to
    a control tick that is due: ``give_way.py``)."""
    give_way.now()
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
    key = (base, *_content(self, y))
    rows: dict[int, tuple[Any, Strip]] | None = self.__dict__.get("_arbiter_rows")
    if rows is None:
        rows = self.__dict__["_arbiter_rows"] = {}
    kept = rows.get(y)
    if kept is not None and kept[0] == key:
        return kept[1]
    strip = _render_line(self, y)
    rows[y] = (key, strip)
    return strip


def _content(canvas: Canvas, y: int) -> tuple[str, str]:
    """Row ``y``'s characters and styles, each as one string."""
    return "".join(canvas._buffer[y]), SEP.join(canvas._styles[y])


def _changed_rows(canvas: Canvas) -> list[int]:
    """The rows whose content differs from what was last painted (never painted: changed)."""
    rows: dict[int, tuple[Any, Strip]] = canvas.__dict__.get("_arbiter_rows", {})
    changed = []
    for y in range(canvas._canvas_size.height):
        kept = rows.get(y)
        if kept is None or kept[0][1:] != _content(canvas, y):
            changed.append(y)
    return changed


@contextmanager
def changed_rows_only(canvases: Iterable[Canvas]) -> Iterator[None]:
    """Draw on ``canvases`` inside this block: each is then refreshed on the rows that changed only
    (the library refreshes the whole canvas on every change, and Textual then styles and composes
    every row again). A canvas whose size changed is refreshed whole. Without :func:`install`, or on
    another release, it does nothing special."""
    held = list(canvases) if _installed else []
    sizes = [canvas._canvas_size for canvas in held]
    for canvas in held:
        canvas._refreshes_pending += 1  # the library's own batching: refresh() does nothing meanwhile
    try:
        yield
    finally:
        for canvas, size in zip(held, sizes, strict=True):
            canvas._refreshes_pending -= 1
            if canvas._refreshes_pending:
                continue
            if canvas._canvas_size != size:
                canvas.refresh()
                continue
            if not canvas._canvas_size.area:  # a margin of no rows: nothing to paint
                continue
            width = max(canvas.size.width, canvas._canvas_size.width)
            regions = [Region(0, y, width, 1) for y in _changed_rows(canvas)]
            if regions:
                canvas.refresh(*regions)


def install() -> bool:
    """Patch ``Canvas.render_line`` (once; idempotent). False when this release was not checked."""
    try:
        release = version("textual-hires-canvas")
    except PackageNotFoundError:
        return False
    if release not in CHECKED:
        return False
    global _installed
    _installed = True
    Canvas.render_line = _render_line_cached  # type: ignore[method-assign]  # the patch, on purpose
    Canvas.render_lines = _render_lines_once  # type: ignore[method-assign]  # the patch, on purpose
    return True
