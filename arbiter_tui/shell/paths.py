"""Path completion for a text input: the rest of the first entry of the typed directory that starts with
what was typed (directories end with ``/``), shown as Textual's suggestion (→ takes it)."""

from __future__ import annotations

import os

from textual.suggester import Suggester

MAX_ENTRIES = 2000  # a directory this large is not listed whole for a suggestion


class PathSuggester(Suggester):
    def __init__(self) -> None:
        super().__init__(use_cache=False, case_sensitive=True)  # the file system changes

    async def get_suggestion(self, value: str) -> str | None:
        return complete(value)


def complete(value: str) -> str | None:
    """``value`` completed to the first (sorted) entry of its directory that starts with its last part;
    None when none does. ``~`` is expanded in the lookup, kept in the text."""
    if not value:
        return None
    head, tail = os.path.split(value)
    where = os.path.expanduser(head) if head else "."
    try:
        with os.scandir(where) as entries:
            names = []
            for n, entry in enumerate(entries):
                if n >= MAX_ENTRIES:
                    break
                if entry.name.startswith(tail) and (tail.startswith(".") or not entry.name.startswith(".")):
                    names.append(entry.name + ("/" if entry.is_dir() else ""))
    except OSError:
        return None
    names.sort()
    for name in names:
        if name != tail:
            return os.path.join(head, name) if head else name
    return None
