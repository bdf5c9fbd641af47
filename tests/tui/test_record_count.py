"""The status line's sample count is live at every size (issue 46, item 3): it was stuck at the count of
the first frame through a whole mission at 80x24 and 120x36, where no screen part that changes slowly
is shown (the count followed only those)."""

import re

import pytest

from ..support.tui import until
from .test_goals_and_comparison import drive, sim_app


def rec(app) -> int:
    text = str(app.screen.query_one("#status").render())
    return int(re.search(r"REC (\d+)", text).group(1))


@pytest.mark.parametrize("size", [(80, 24), (120, 36)], ids=["80x24", "120x36"])
async def test_the_sample_count_follows_a_mission(tmp_path, size):
    app, clock = sim_app(tmp_path)
    app.sampler.clock = clock  # the frame sampler's clock: simulated time, as the session's
    async with app.run_test(size=size) as pilot:
        await pilot.press("a", "g")
        shown = []
        for _ in range(4):
            drive(app, clock, 2.0)
            app.sample_frame()
            await pilot.pause()
            shown.append(rec(app))
        assert await until(pilot, lambda: rec(app) == len(app.session.store))
        assert shown == sorted(shown) and len(set(shown)) == len(shown), shown  # it moved every time


async def test_the_export_chooser_says_what_the_file_gets_and_the_header_agrees(tmp_path):
    """Issue 54, item 7: "Export N samples" is what the file gets (the samples recorded while the chooser
    is open are not in it, nor in its count), and the header said N when it opened ("Export 73" beside
    "REC 69", and a file of 80)."""
    import json

    from textual.widgets import Static

    from arbiter_tui.shell.screens.export import ExportChooser

    app, clock = sim_app(tmp_path)
    app.sampler.clock = clock
    store = app.session.store
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("a", "g")
        drive(app, clock, 2.0)
        app.sample_frame()
        await pilot.press("2")
        drive(app, clock, 1.0)  # recorded since the last frame: the header has not said them yet
        n = len(store)
        await pilot.press("ctrl+s")
        assert await until(pilot, lambda: isinstance(app.screen, ExportChooser))
        said = str(app.screen.query(Static).first().render())
        header = str(app.screen_stack[-2].query_one("#status").render())
        assert said == f"Export {n} samples as:"
        assert re.search(r"REC (\d+)", header).group(1) == str(n), header
        drive(app, clock, 1.0)  # still recording while the user chooses
        assert len(store) > n
        await pilot.press("j")
        assert await until(pilot, lambda: list(tmp_path.glob("*.json")))
        (written,) = tmp_path.glob("*.json")
        assert len(json.loads(written.read_text())["dataPoints"]) == n
