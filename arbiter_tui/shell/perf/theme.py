"""The app's current theme, found without copying the theme registry.

Textual 8.2.8's ``App.current_theme`` looks its theme up through ``available_themes``, which copies the
registry (every built-in theme) twice a call, and the styles cache calls it for every line it renders
(``ansi_theme``): 8.5 % of the analytics screen's render time (py-spy, 200x60, a mission driving).
:class:`RegistryTheme` answers from the registry directly when the theme is a single registered name,
which is what the console sets, and leaves everything else (comma-separated names, the fallback) to
Textual.
"""

from __future__ import annotations

import textual
from textual.app import App
from textual.theme import Theme

CHECKED = ("8.2.8",)  # the releases whose App keeps its registry in ``_registered_themes``


_installed = False  # set once by install(): ``textual.__version__`` reads package metadata per access


def checked() -> bool:
    """Whether this Textual release was checked (``RegistryTheme`` falls back to Textual otherwise)."""
    return textual.__version__ in CHECKED


def install() -> bool:
    """Turn the registry lookup on (once) when this release was checked; whether it took."""
    global _installed
    _installed = checked()
    return _installed


class RegistryTheme(App[None]):
    """Mixed into the console's app (before ``App``)."""

    @property
    def current_theme(self) -> Theme:
        if not _installed:  # not installed, or a release not checked: Textual's own lookup
            return super().current_theme
        theme = self._registered_themes.get(self.theme)  # Textual 8.2.8's registry (private)
        return theme if theme is not None else super().current_theme
