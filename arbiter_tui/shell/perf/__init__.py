"""Where the console reaches inside Textual and its plotting library for speed: every such patch in one
place, each applied only to the releases it was checked against, installed explicitly at start-up
(:func:`install`, from ``make_app``), never as a side effect of an import.

- ``strips``: Textual's strips freed by reference counting, not by full garbage collections;
- ``canvas_rows``: a plot canvas's unchanged rows keep their strips (textual-hires-canvas);
- ``theme``: the app's current theme read from the registry, not a copy of it per line;
- ``give_way``: a paint gives way to a due control tick (a hook the widgets call; no patch of Textual);
- ``heap``: the console's long-lived heap frozen out of the collector's walks.

Each patch's test fails on a release it does not know (``tests/unit/test_perf.py``): upgrading
Textual (pinned in pyproject.toml) makes a patch's test red, never silently drops the patch and its
test together.
"""

from __future__ import annotations

from importlib.metadata import version

import textual

from . import canvas_rows, strips, theme

_installed: dict[str, bool] | None = None


def releases() -> dict[str, str]:
    """The releases the patches look at, installed here."""
    return {"textual": textual.__version__, "textual-hires-canvas": version("textual-hires-canvas")}


def install() -> dict[str, bool]:
    """Apply every patch this install's releases were checked for (once); which ones took."""
    global _installed
    if _installed is None:
        _installed = {
            "strips": strips.install(), "canvas_rows": canvas_rows.install(), "theme": theme.install()
        }  # fmt: skip
    return dict(_installed)
