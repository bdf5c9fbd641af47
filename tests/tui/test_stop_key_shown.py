"""One stop key, shown wherever the user is, typing or not (issue 54, items 1-2): in every context where
``space`` and ``k`` are text -- the palette, the topics filter, the goal dialog, the open-a-recording
dialog -- the footer the user sees names ``^k`` once a letter is typed (the placeholder that said it is
gone then), shows no key that is text there, and ``ctrl+k`` stops a running mission at once while the
letters typed stay as they were."""

import pytest
from textual.command import CommandPalette
from textual.widgets import Input

from arbiter_tui.shell.screens.goal import GoalPrompt
from arbiter_tui.shell.screens.open_file import OpenRecording

from ..support.tui import screen_text, still_app, until

# (screen, keys that open the context, what is then in front)
CONTEXTS = [
    ("1", ("ctrl+p",), CommandPalette),
    ("4", ("slash",), Input),  # the topics filter
    ("1", ("t",), GoalPrompt),
    ("2", ("f",), OpenRecording),
]


def opened(app, what) -> bool:
    if what is Input:
        return isinstance(app.focused, Input)
    return isinstance(app.screen, what)


@pytest.mark.parametrize("size", [(80, 24), (200, 60)], ids=["80x24", "200x60"])
@pytest.mark.parametrize(("screen", "opening", "what"), CONTEXTS, ids=lambda c: getattr(c, "__name__", None))
async def test_every_input_names_the_stop_key_while_typing_and_ctrl_k_stops(
    tmp_path, size, screen, opening, what
):
    app = still_app(tmp_path)
    session = app.session
    async with app.run_test(size=size) as pilot:
        session.select_algorithm("stanley")
        session.select_mission("corner")
        assert app.go() and session.loop.running
        await pilot.press(screen, *opening)
        assert await until(pilot, lambda: opened(app, what))
        await pilot.press("a", "space", "k")  # text here: typed, and the mission drives on
        assert app.focused.value == "a k" and session.loop.running
        await pilot.pause()
        footer = screen_text(app).splitlines()[-1]
        assert "^k Stop robot" in footer, footer
        text_keys = [word for word in footer.split() if len(word) == 1]  # "a Algo", "1 Drive", "? Help"
        assert not text_keys, f"the footer shows keys that are text here: {footer!r}"
        await pilot.press("ctrl+k")
        assert not session.loop.running and session.loop.command == (0.0, 0.0)
        assert session.link.sent[-1] == (0.0, 0.0)
        assert app.focused.value == "a k", "ctrl+k stopped the robot and typed nothing"
