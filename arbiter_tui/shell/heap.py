"""The console's long-lived heap, out of the garbage collector's way."""

from __future__ import annotations

import gc

FREEZE_AFTER_S = 2.0  # after a screen's first showing: its widgets and caches are made by then


def freeze_heap() -> None:
    """Move every object alive now into the garbage collector's permanent generation.

    A full (generation 2) collection walks every tracked object while holding the GIL; the console's
    heap (Textual's widgets, styles, caches) made that 100-500 ms on a Pi-class CPU (bench/pi.py, gc
    callbacks), during which the session thread could not send a command. The widgets and caches made
    at start and on each screen's first showing live as long as the console, so they need never be walked
    again: a full collection then only walks what was made since. Cheap (a list splice) and called a
    handful of times (at start, and once per screen), so the garbage frozen with them stays a one-off."""
    gc.freeze()
