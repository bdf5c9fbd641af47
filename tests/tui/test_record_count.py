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
