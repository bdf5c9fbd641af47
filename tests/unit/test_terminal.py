"""``arbiter_tui.terminal``: the console's writes with each style change said once give the person the
same picture. Checked with a terminal emulator (pyte) on what Textual writes for the console's screens
(the dashboard with its plots at 200x60, each screen at 80x24) and on random streams of the sequences
Textual and other programs write: every cell the same character with the same look (a blank cell's look
is its background, and its colour where it is underlined, reversed or struck through)."""

from __future__ import annotations

import pyte
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from arbiter_tui.terminal import RESET, apply, change, fewer_sgr

from ..support.tui import still_app


def screen_of(stream: str, cols: int, rows: int) -> pyte.Screen:
    screen = pyte.Screen(cols, rows)
    pyte.Stream(screen).feed(stream)
    return screen


def looks(char: pyte.screens.Char) -> tuple[object, ...]:
    if char.data == " " and not (char.reverse or char.underscore or char.strikethrough):
        return (" ", char.bg)  # what a blank shows: its background
    return tuple(char)


def same_picture(a: str, b: str, cols: int, rows: int) -> list[tuple[int, int]]:
    """The cells where ``a`` and ``b`` leave different pictures (empty: none)."""
    sa, sb = screen_of(a, cols, rows), screen_of(b, cols, rows)
    differ = [
        (x, y) for y in range(rows) for x in range(cols) if looks(sa.buffer[y][x]) != looks(sb.buffer[y][x])
    ]
    cursor = (sa.cursor.x, sa.cursor.y) == (sb.cursor.x, sb.cursor.y)
    return differ if cursor else [*differ, (-1, -1)]


def written(app) -> str:
    """What Textual writes to repaint the whole screen (``App._display`` of a full update)."""
    return app.screen._compositor.render_full_update().render_segments(app.console)


@pytest.mark.parametrize(
    ("size", "keys"),
    [((200, 60), []), ((80, 24), []), ((80, 24), ["2"]), ((80, 24), ["3"]), ((100, 30), ["question_mark"])],
    ids=["dashboard-200x60", "control-80x24", "analytics-80x24", "latency-80x24", "help-100x30"],
)
async def test_each_screen_the_same_picture_in_fewer_bytes(size, keys):
    app = still_app()
    async with app.run_test(size=size) as pilot:
        await pilot.press(*keys)
        await pilot.pause()
        before = written(app)
    after = fewer_sgr(before)
    assert same_picture(before, after, *size) == []
    assert "\x1b[0m\x1b[" not in after  # no reset followed by a whole style again
    # Textual's own output: a reset and the whole style around every run. The dashboard's plots are most
    # of its bytes: at least a third fewer; every screen at least a fifth fewer
    assert len(after.encode()) < len(before.encode()) * (0.67 if size == (200, 60) else 0.8)


COLOURS = st.sampled_from(["31", "97", "38;5;24", "38;5;253", "38;2;10;20;30", "39"])
BACKS = st.sampled_from(["44", "48;5;233", "48;2;1;2;3", "49", "103"])
ATTRS = st.sampled_from(["1", "2", "3", "4", "5", "7", "9", "22", "23", "24", "25", "27", "29"])
SGR = st.lists(st.one_of(COLOURS, BACKS, ATTRS, st.just("0"), st.just("")), min_size=1, max_size=4).map(
    lambda ps: f"\x1b[{';'.join(ps)}m"
)
TEXT = st.sampled_from(["x", "ab", "   ", " ", "⣿⡇", "█", " y ", "\r\n"])
OTHER = st.one_of(
    st.builds(lambda y, x: f"\x1b[{y};{x}H", st.integers(1, 8), st.integers(1, 30)),
    st.sampled_from(["\x1b[K", "\x1b[2K", "\x1b[3X", "\x1b[?25l", "\x1b[?2026h", "\x1b[2C", "\x1b[A"]),
)


@settings(max_examples=400, deadline=None)
@given(st.lists(st.one_of(SGR, TEXT, OTHER), max_size=60))
def test_any_stream_leaves_the_same_picture_and_the_same_style_after_it(parts):
    stream = "".join(parts) + "\x1b[0m"  # a write of Textual's ends reset
    after = fewer_sgr(stream)
    assert same_picture(stream, after, 30, 8) == []
    # the next write starts from the same state: text after both paints alike
    assert same_picture(stream + "z ", after + "z ", 30, 8) == []
    # and a stream that ends styled is left styled as the original left it
    styled = "".join(parts)
    assert same_picture(styled + "z  ", fewer_sgr(styled) + "z  ", 30, 8) == []


def test_a_code_it_cannot_read_passes_as_it_came_until_a_reset():
    stream = "\x1b[38;5;24ma\x1b[4:3mb\x1b[38;5;24mc\x1b[0m\x1b[38;5;24md\x1b[0m\x1b[38;5;24me\x1b[0m"
    after = fewer_sgr(stream)
    # the curly underline and everything after it verbatim, up to the reset; then said once again
    assert after == "\x1b[38;5;24ma\x1b[4:3mb\x1b[38;5;24mc\x1b[0m\x1b[38;5;24mde\x1b[0m"
    assert apply(RESET, "4:3") is None and apply(RESET, "38;5") is None and apply(RESET, "73") is None


def test_private_sequences_and_hyperlinks_pass_untouched():
    link, unlink = "\x1b]8;id=1;https://x\x1b\\", "\x1b]8;;\x1b\\"
    stream = f"\x1b[>4;1m{link}\x1b[1mlink\x1b[0m{unlink}\x1b[6n"
    # (the reset may come later, before the next text: it paints nothing)
    assert fewer_sgr(stream) == f"\x1b[>4;1m{link}\x1b[1mlink{unlink}\x1b[6n\x1b[0m"


def test_a_change_is_the_shorter_of_a_step_and_a_reset():
    bold_blue = apply(RESET, "1;38;5;24")
    assert change(bold_blue, apply(RESET, "38;5;24")) == "\x1b[22m"
    # 22 clears bold and dim alike: dim again after it
    assert change(apply(RESET, "2;1;38;5;24"), apply(RESET, "2;38;5;24")) == "\x1b[22;2m"
    assert change(bold_blue, RESET) == "\x1b[0m"
    assert change(apply(RESET, "1;4;7;9;38;5;24;48;5;233"), apply(RESET, "31")) == "\x1b[0;31m"


def test_the_driver_writes_the_shorter_stream_and_the_original_if_the_rewrite_fails(monkeypatch, caplog):
    import arbiter_tui.terminal as terminal

    class Recorder:
        def __init__(self) -> None:
            self.written: list[str] = []

        def write(self, data: str) -> None:
            self.written.append(data)

    driver = terminal.fewer_bytes(Recorder)()
    stream = "\x1b[38;5;24ma\x1b[0m\x1b[38;5;24mb\x1b[0m"
    driver.write(stream)
    assert driver.written == ["\x1b[38;5;24mab\x1b[0m"]

    def broken(data: str) -> str:
        raise ValueError("a bug")

    monkeypatch.setattr(terminal, "fewer_sgr", broken)
    monkeypatch.setattr(terminal, "_failed", False)
    driver.write(stream)
    driver.write(stream)
    assert driver.written[1:] == [stream, stream]  # the screen as Textual made it, never lost
    assert caplog.text.count("the rewrite failed") == 1  # said once
