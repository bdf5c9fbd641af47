"""The themes the console offers (the config file's ``theme`` is checked against them): Textual's own,
named here so that nothing outside the shell imports Textual."""

from __future__ import annotations

from textual.theme import BUILTIN_THEMES


def names() -> list[str]:
    return list(BUILTIN_THEMES)
