"""The console's current theme comes from the registry without copying it (shell/theme.py), and is
always the theme Textual itself would find."""

from textual.app import App

from arbiter_tui.shell.perf.theme import RegistryTheme


class Plain(RegistryTheme):
    pass


async def test_the_current_theme_is_textuals_for_every_registered_theme():
    app = Plain()
    async with app.run_test():
        names = list(app.available_themes)
        assert len(names) > 5
        for name in names:
            app.theme = name
            assert app.current_theme is App.current_theme.fget(app)  # type: ignore[attr-defined]
            assert app.current_theme.name == name


async def test_a_name_the_registry_lacks_is_left_to_textual():
    app = Plain()
    async with app.run_test():
        app.theme = "nord"
        app._registered_themes.pop("nord")  # as if unregistered under it: Textual's fallback answers
        assert app.current_theme.name == "textual-dark"
