"""Textual's strips, patched (arbiter_tui.shell.strips): the same results as Textual's own methods,
and no strip kept alive by a reference to itself."""

from __future__ import annotations

import sys

import pytest
from rich.segment import Segment
from rich.style import Style
from textual.strip import Strip

from arbiter_tui.shell.perf import strips


def setup_module() -> None:
    # not a skip: on a Textual release the patch does not know, these tests fail (tests/unit/test_perf.py
    # says which release); the patch is then checked again, or removed
    assert strips.install(), "a Textual release the strips patch was not checked on"

RED = Style(color="red")


def make(*texts: str) -> Strip:
    return Strip([Segment(t, RED) for t in texts])


def freed_without_collection(use) -> bool:
    """Whether a strip that ``use`` was called on is freed by reference counting alone: ``use`` left
    no reference to it behind (a strip has no weak references; its own caches are where one would
    hide)."""
    strip = make("abc", "defg")
    before = sys.getrefcount(strip)
    use(strip)
    return sys.getrefcount(strip) == before


@pytest.mark.parametrize(
    ("name", "use"),
    [
        ("divide at its end", lambda s: s.divide([s.cell_length])),
        ("divide past its end", lambda s: s.divide([s.cell_length, s.cell_length + 5])),
        ("crop_extend over its length", lambda s: s.crop_extend(0, s.cell_length, None)),
        ("crop_extend from before its start", lambda s: s.crop_extend(-2, s.cell_length, None)),
        ("divide inside", lambda s: s.divide([2, s.cell_length])),
        ("crop_extend inside", lambda s: s.crop_extend(1, 5, None)),
        ("crop_extend past its end", lambda s: s.crop_extend(0, 12, RED)),
    ],
)
def test_no_strip_refers_to_itself(name: str, use) -> None:
    assert freed_without_collection(use), name


def test_textual_alone_keeps_such_a_strip_in_its_own_cache() -> None:
    """What the patch is for: the same call on Textual's own method leaves a reference behind (if
    this fails, Textual no longer makes the cycle and the patch can go)."""
    strip = make("abc", "defg")
    before = sys.getrefcount(strip)
    strips._crop_extend(strip, 0, strip.cell_length, None)
    assert sys.getrefcount(strip) == before + 1


def texts(strip: Strip) -> list[tuple[str, Style | None]]:
    return [(seg.text, seg.style) for seg in strip]


@pytest.mark.parametrize("cuts", [[7], [7, 9], [2, 7], [0, 3, 7], [3], [1, 2, 3, 4, 5, 6, 7], [10]])
def test_divide_gives_what_textual_gives(cuts: list[int]) -> None:
    ours = make("abc", "defg").divide(cuts)
    theirs = strips._divide(make("abc", "defg"), cuts)
    assert [texts(s) for s in ours] == [texts(s) for s in theirs]
    assert [s.cell_length for s in ours] == [s.cell_length for s in theirs]


@pytest.mark.parametrize(("start", "end"), [(0, 7), (-1, 7), (0, 3), (2, 7), (0, 10), (3, 12), (5, 5)])
def test_crop_extend_gives_what_textual_gives(start: int, end: int) -> None:
    ours = make("abc", "defg").crop_extend(start, end, RED)
    theirs = strips._crop_extend(make("abc", "defg"), start, end, RED)
    assert texts(ours) == texts(theirs) and ours.cell_length == theirs.cell_length
