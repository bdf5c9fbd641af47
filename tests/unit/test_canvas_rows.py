"""The canvases' row cache (arbiter_tui.shell.canvas_rows): each row as the library draws it, the same
strip again for a row that did not change, a new one for any change to its cells or their styles."""

from __future__ import annotations

from textual.app import App, ComposeResult
from textual.strip import Strip
from textual_hires_canvas.canvas import Canvas

from arbiter_tui.shell.perf import canvas_rows


def setup_module() -> None:
    # not a skip: a textual-hires-canvas release the patch does not know fails here (test_perf.py)
    assert canvas_rows.install(), "a textual-hires-canvas release the canvas patch was not checked on"

W, H = 12, 4


class One(App[None]):
    def compose(self) -> ComposeResult:
        yield Canvas(W, H)


def cells(strip: Strip) -> list[tuple[str, str]]:
    return [(seg.text, str(seg.style)) for seg in strip]


def library(canvas: Canvas) -> list[list[tuple[str, str]]]:
    return [cells(canvas_rows._render_line(canvas, y)) for y in range(H)]


async def test_rows_as_the_library_draws_them_and_unchanged_rows_kept() -> None:
    async with One().run_test(size=(20, 6)) as pilot:
        canvas = pilot.app.query_one(Canvas)
        canvas.draw_line(0, 0, W - 1, 0, char="#", style="red")
        canvas.set_pixel(3, 2, char="o", style="green")
        first = [canvas.render_line(y) for y in range(H)]
        assert [cells(s) for s in first] == library(canvas)
        assert "#" * W in "".join(seg.text for seg in first[0])

        again = [canvas.render_line(y) for y in range(H)]
        assert all(a is b for a, b in zip(again, first, strict=True))  # nothing changed: nothing built


async def test_any_change_to_a_row_builds_it_again() -> None:
    async with One().run_test(size=(20, 6)) as pilot:
        canvas = pilot.app.query_one(Canvas)
        canvas.set_pixel(3, 2, char="o", style="green")
        before = [canvas.render_line(y) for y in range(H)]

        canvas.set_pixel(5, 2, char="x", style="green")  # a new cell in row 2
        after = [canvas.render_line(y) for y in range(H)]
        assert after[2] is not before[2] and "x" in after[2].text
        assert all(after[y] is before[y] for y in (0, 1, 3))
        assert [cells(s) for s in after] == library(canvas)

        canvas.set_pixel(5, 2, char="x", style="blue")  # the same character, another style
        restyled = canvas.render_line(2)
        assert restyled is not after[2]
        assert cells(restyled) == library(canvas)[2] != cells(after[2])

        canvas.reset()  # cleared: blank rows, none of the old strips
        assert [cells(canvas.render_line(y)) for y in range(H)] == library(canvas)
        assert "x" not in canvas.render_line(2).text


def shown(app: App[None]) -> str:
    """What the screen shows: its text, from each widget's painted (cached) lines."""
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


async def test_a_redraw_marks_only_the_rows_that_changed_and_the_screen_shows_them() -> None:
    async with One().run_test(size=(20, 6)) as pilot:
        canvas = pilot.app.query_one(Canvas)
        canvas.draw_line(0, 0, W - 1, 0, char="#", style="red")
        canvas.set_pixel(3, 2, char="o", style="green")
        await pilot.pause()  # painted: every row's strip kept, nothing dirty
        assert not canvas._styles_cache._dirty_lines

        with canvas_rows.changed_rows_only([canvas]):  # as a plot redraws: cleared, all drawn again
            canvas.reset()
            canvas.draw_line(0, 0, W - 1, 0, char="#", style="red")
            canvas.set_pixel(3, 2, char="o", style="green")
            canvas.set_pixel(7, 3, char="x", style="green")  # the one change
        assert canvas._styles_cache._dirty_lines == {3}
        await pilot.pause()
        assert "x" in shown(pilot.app) and "o" in shown(pilot.app)

        with canvas_rows.changed_rows_only([canvas]):  # nothing changed: nothing to paint
            canvas.reset()
            canvas.draw_line(0, 0, W - 1, 0, char="#", style="red")
            canvas.set_pixel(3, 2, char="o", style="green")
            canvas.set_pixel(7, 3, char="x", style="green")
        assert not canvas._styles_cache._dirty_lines

        with canvas_rows.changed_rows_only([canvas]):  # the line gone: row 0 repainted, blank on screen
            canvas.reset()
            canvas.set_pixel(3, 2, char="o", style="green")
        assert canvas._styles_cache._dirty_lines == {0, 3}
        await pilot.pause()
        assert "#" not in shown(pilot.app) and "x" not in shown(pilot.app)
