"""Textual's strips without reference cycles: the same results, freed as soon as they are dropped.

A :class:`textual.strip.Strip` caches what it derives from itself. Two of its methods can derive the
strip itself and cache it in its own cache: ``divide`` with the single cut at its end (the compositor
cuts every line of every widget each frame, and a widget that overlaps nothing has exactly that cut),
and ``crop_extend`` over its whole length. Such a strip refers to itself, so reference counting never
frees it and only a full garbage collection does: ~4,000 objects a second on the dashboard at 200x60,
each strip with its seven caches. A full collection holds the GIL for its whole walk, so on a
Pi-class CPU quota it delayed the robot's commands by 150-260 ms every few seconds (docs/BENCHMARKS.md,
``bench/gcprobe``).

:func:`install` answers those two cases before the cache is consulted, with exactly what the original
would return (the strip itself; ``divide`` a new one-element list of it), and leaves every other case to
Textual. It is applied only to the Textual release it was checked against (``CHECKED``): another
release keeps its own code, and ``tests/unit/test_strips.py`` says whether the cycle is back.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import textual
from rich.style import Style
from textual.strip import Strip

CHECKED = ("8.2.8",)

_divide = Strip.divide
_crop_extend = Strip.crop_extend


def _divide_acyclic(self: Strip, cuts: Iterable[int]) -> Sequence[Strip]:
    cuts = list(cuts)
    length = self.cell_length
    if [cut for cut in cuts if cut <= length] == [length]:
        return [self]
    return _divide(self, cuts)


def _crop_extend_acyclic(self: Strip, start: int, end: int, style: Style | None) -> Strip:
    if start <= 0 and end == self.cell_length:
        return self
    return _crop_extend(self, start, end, style)


def install() -> bool:
    """Patch ``Strip`` (once; idempotent). False when this Textual release was not checked."""
    if textual.__version__ not in CHECKED:
        return False
    Strip.divide = _divide_acyclic  # type: ignore[method-assign]  # the patch, on purpose
    Strip.crop_extend = _crop_extend_acyclic  # type: ignore[method-assign]  # the patch, on purpose
    return True
