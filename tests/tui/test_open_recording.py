"""A recording opened on the analytics screen (issue 47, item 5): `f`, a path (→ completes it), enter;
the screen then shows the file's runs ranked and plotted exactly as `arbiter-tui stats` grades them,
marked as a file on the screen and in the status line, until escape brings the live session back."""

import json

import pytest

from arbiter_core.simulator import DiffDriveSimulator
from arbiter_tui.analytics.grade import grade
from arbiter_tui.analytics.model import stats_of_points
from arbiter_tui.cli import main
from arbiter_tui.session.recording import recording_view
from arbiter_tui.shell.paths import complete
from arbiter_tui.shell.widgets.analytics import CompareTable, FileBanner

from ..support.bags import T0_NS, Recording, drive, write_bag
from ..support.tui import screen_text, still_app, until


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    """Two observed runs of a robot-side controller: to (2, 1), then on to (3, -1) from there."""
    sim = DiffDriveSimulator()
    first = drive("pure_pursuit", goal=(2.0, 1.0), seconds=15.0, sim=sim)
    second = drive("pure_pursuit", goal=(3.0, -1.0), seconds=15.0, t0_ns=T0_NS + 16_000_000_000, sim=sim)
    rec = Recording(first.messages + second.messages, first.poses + second.poses)
    return write_bag(tmp_path_factory.mktemp("bags") / "nav2_run", rec, "mcap")


LIVE = "Back to the live session"


@pytest.fixture(scope="module")
def no_goal(tmp_path_factory):
    """Odometry alone: no goal, no plan, so no reference for an error."""
    rec = drive("pure_pursuit", goal=(2.0, 1.0), seconds=8.0)
    only = Recording([m for m in rec.messages if m[0] == "/odom"], rec.poses)
    return write_bag(tmp_path_factory.mktemp("bags") / "odom_only", only, "mcap")


def palette_titles(app) -> list[str]:
    """The palette's command titles as it would list them now."""
    return [c.title for c in app.get_system_commands(app.screen)]


def stats_json(path, capsys) -> dict:
    assert main(["stats", str(path), "--by", "run", "--json"]) == 0
    return json.loads(capsys.readouterr().out)


async def test_a_bag_opened_on_screen_2_is_graded_as_stats_grades_it(bag, tmp_path, capsys):
    cli = stats_json(bag, capsys)  # what the command line prints, before the app owns the terminal
    app = still_app(tmp_path)
    async with app.run_test(size=(120, 36)) as pilot:
        assert LIVE not in palette_titles(app)  # nothing to leave yet
        await pilot.press("2", "f")
        await pilot.press(*str(bag), "enter")
        assert await until(pilot, lambda: bool(app.frame.analytics.source), timeout=30)
        assert LIVE in palette_titles(app)
        view = app.frame.analytics
        assert view.source.startswith("nav2_run (ros2 bag")
        ours = {f"run {r.id}": r for r in view.runs}
        assert set(ours) == {k for k in cli if k.startswith("run ")} and len(ours) == 2
        for key, run in ours.items():
            for name, value in run.stats.as_dict().items():
                assert value == pytest.approx(cli[key][name], rel=1e-9, abs=1e-12), (key, name)
            assert run.outcome == cli[key]["outcome"]
        graded = grade(bag)
        assert view.stats == stats_of_points(graded.export.points)  # the cards: stats FILE's overall
        table = app.screen.query_one(CompareTable).table
        goals = ["goal (+2.00, +1.00)", "★ observed", "goal (+3.00, -1.00)", "★ observed"]
        assert [r[0] for r in table.rows] == goals  # each goal a mission, its best starred, as stats ranks
        banner = str(app.screen.query_one(FileBanner).render())
        assert banner.startswith("FILE nav2_run") and "esc: the live session" in banner
        assert "FILE nav2_run" in str(app.screen.query_one("#status").render())
        assert "escape" in {b.binding.key for b in app.screen.active_bindings.values() if b.enabled}
        await pilot.press("escape")
        assert await until(pilot, lambda: not app.frame.analytics.source)
        assert app.frame.analytics.runs == app.session.store.runs()  # the live session's again
        assert LIVE not in palette_titles(app)


async def test_a_file_that_cannot_be_read_is_one_line_and_the_live_session_stays(tmp_path):
    bad = tmp_path / "broken.mcap"
    bad.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 40)
    app = still_app(tmp_path)
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("2", "f", *str(bad), "enter")
        said = lambda: [str(n.message) for n in app._notifications if "cannot open" in str(n.message)]  # noqa: E731
        assert await until(pilot, said, 30)
        (line,) = said()
        assert "\n" not in line and str(bad) in line
        assert not app.frame.analytics.source


def test_a_path_is_completed_from_its_directory(tmp_path):
    (tmp_path / "rosbag2_a").mkdir()
    (tmp_path / "rosbag2_b.mcap").write_bytes(b"")
    (tmp_path / ".hidden").write_bytes(b"")
    assert complete(f"{tmp_path}/ros") == f"{tmp_path}/rosbag2_a/"
    assert complete(f"{tmp_path}/rosbag2_b") == f"{tmp_path}/rosbag2_b.mcap"
    assert complete(f"{tmp_path}/nothing") is None and complete("") is None
    assert complete(f"{tmp_path}/.h") == f"{tmp_path}/.hidden"  # hidden only when asked for


def test_a_recording_on_screen(snap_compare, bag):
    app = still_app()
    app.sampler.recording_opened(recording_view(grade(bag)))
    assert snap_compare(app, terminal_size=(120, 36), press=["2"])


async def test_a_recording_with_no_goal_shows_no_error_and_no_live_latency(no_goal, tmp_path):
    """Issue 54, item 4: the file view of a recording with no goal or plan says "—" and why for the error
    stats (not 0.000), and shows nothing of the live session's link (its latency line and plot)."""
    app = still_app(tmp_path)
    async with app.run_test(size=(120, 36)) as pilot:
        await pilot.press("2")
        live = screen_text(app)
        assert "error vs latency" in live  # the live session's link line
        await pilot.press("f", *str(no_goal), "enter")
        assert await until(pilot, lambda: bool(app.frame.analytics.source), timeout=30)
        await pilot.pause()
        shown = screen_text(app)
        for label in ("avg e_d", "p95 e_d", "std e_d", "avg |e_θ|"):
            assert f"{label} —" in shown, shown
        assert "0.000 m" not in shown
        assert "no reference: no goal or plan in the recording" in shown
        assert "error vs latency" not in shown and "latency (ms)" not in shown
        await pilot.press("escape")
        assert await until(pilot, lambda: not app.frame.analytics.source)
        await pilot.pause()
        assert "error vs latency" in screen_text(app)
