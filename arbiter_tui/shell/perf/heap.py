"""The console's long-lived heap, out of the garbage collector's way."""

from __future__ import annotations

import gc


def freeze_heap() -> None:
    """Move every object alive now into the garbage collector's permanent generation.

    Called once the start-up heap is on screen, and after each screen's first showing (its widgets
    and caches live as long as the console): a full collection then never walks them again. The
    session's collector (``session/collector.py``) freezes what survives its collections the same way
    and, while the console sends no commands, walks the whole heap to free what ended in a cycle."""
    gc.freeze()
