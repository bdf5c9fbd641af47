"""Snapshots of every screen at fixed sizes with deterministic data (no timers, no clock on screen)."""

import math

import pytest

from arbiter_tui.link.base import RECONNECTING

from ..support.tui import RecordingLink, seeded_store, show_frame, still_app, tracker_said

SIZES = [(100, 30), (80, 24)]


@pytest.mark.parametrize("size", SIZES, ids=["100x30", "80x24"])
@pytest.mark.parametrize(
    "keys", [[], ["2"], ["3"], ["question_mark"]], ids=["control", "analytics", "latency", "help"]
)
def test_screen(snap_compare, size, keys):
    assert snap_compare(still_app(), terminal_size=size, press=keys)


def test_latency_screen_when_tracker_unreachable(snap_compare):
    app = still_app(tracker_view=False)
    app.tracker.view.fail("connection refused")
    tracker_said(app)
    assert snap_compare(app, terminal_size=(100, 30), press=["3"])


@pytest.mark.parametrize("keys", [[], ["3"]], ids=["control", "latency"])
def test_link_down_is_shown_on_each_screen(snap_compare, keys):
    """The rosbridge link lost: red status line, a banner on the control screen, the latency
    screen says this console's figures have stopped (the tracker's are still shown)."""
    app = still_app(link=RecordingLink(state=RECONNECTING))
    assert snap_compare(app, terminal_size=(100, 30), press=keys)


def test_client_side_simulation_shows_latency_na(snap_compare):
    assert snap_compare(still_app(mode="sim"), terminal_size=(100, 30), press=["3"])


def test_terminal_too_small(snap_compare):
    assert snap_compare(still_app(), terminal_size=(60, 20))


@pytest.mark.parametrize("size", SIZES, ids=["100x30", "80x24"])
def test_clear_confirmation(snap_compare, size):
    assert snap_compare(still_app(), terminal_size=size, press=["2", "delete"])


def test_export_chooser(snap_compare):
    assert snap_compare(still_app(), terminal_size=(80, 24), press=["2", "ctrl+s"])


@pytest.mark.parametrize("keys", [["a", "g"], ["a", "g", "2"]], ids=["control", "analytics"])
def test_a_mission_run_on_screen(snap_compare, keys):
    assert snap_compare(still_app(), terminal_size=(80, 24), press=keys)


@pytest.mark.parametrize("size", SIZES, ids=["100x30", "80x24"])
def test_comparison_per_run_sorted(snap_compare, size):
    """The comparison per run (v), sorted by time to complete (clicked twice: longest first)."""

    async def per_run_by_time(pilot):
        from arbiter_tui.shell.widgets.analytics import CompareTable

        await pilot.press("2", "v")
        table = pilot.app.screen.query_one(CompareTable)
        table.sort_by("time_s")
        table.sort_by("time_s")
        await pilot.pause()

    assert snap_compare(still_app(), terminal_size=size, run_before=per_run_by_time)


def test_goal_prompt_with_an_error(snap_compare):
    """t: the goal prompt, after a bad entry (the error says what to type)."""
    assert snap_compare(still_app(), terminal_size=(80, 24), press=["t", *"1 x", "enter"])


@pytest.mark.parametrize("paused", [False, True], ids=["recording", "paused"])
def test_analytics_empty_state(snap_compare, paused):
    """Nothing recorded yet: the screen says whether recording is on, and what to do."""
    from arbiter_tui.analytics.store import AnalyticsStore

    app = still_app(store=AnalyticsStore())
    if paused:
        app.session.store.stop_collection()
    assert snap_compare(app, terminal_size=(80, 24), press=["2"])


def test_latency_histogram_of_a_skewed_window(snap_compare):
    """563 fast commands and a few slow ones: a log count axis, no bar where a bin is empty."""
    from .test_trust_screens import SKEWED, latency_app

    assert snap_compare(latency_app(SKEWED), terminal_size=(100, 30), press=["3"])


def test_the_map_with_a_mission_selected(snap_compare):
    """go_to_goal selected (a): the square's waypoints and goal where g will take the robot, in metres."""
    assert snap_compare(still_app(), terminal_size=(100, 30), press=["a"])


DASHBOARD_SIZES = [(160, 45), (200, 60)]


@pytest.mark.parametrize("size", DASHBOARD_SIZES, ids=["160x45", "200x60"])
def test_dashboard(snap_compare, size):
    """The control panel, the map (its drawing, not blank metres) and the topics table (slow, silent and
    quiet rows marked) on top; below, the live comparison beside the link's latency, every figure whole,
    and their plots. At 200x60 the extra rows are the plots', and a trajectory and a histogram join them."""
    from dataclasses import replace

    from .test_topics_screen import QUIET, STATE

    app = still_app()
    app.sampler.topics_polled(replace(STATE, topics=(*STATE.topics, QUIET)))
    assert snap_compare(app, terminal_size=size)


def test_dashboard_with_the_link_down(snap_compare):
    """Stale pose and odometry marked, the banner short, the latency pane saying the link is down: at the
    smallest dashboard, where the banner must still leave every row of the panel in view."""
    app = still_app(link=RecordingLink(state=RECONNECTING))
    assert snap_compare(app, terminal_size=(160, 45))


def test_analytics_marks_the_measured_latency_on_the_error_vs_latency_curve(snap_compare):
    """The curve of a real sweep (square, every controller), and the p95 of the latencies the console
    recorded (the store's, as the app computes it) marked on it, in the plot and in words."""
    from arbiter_core.linkmodel import LinkModel
    from arbiter_tui.analytics.linkcurve import READY, SWEEP_LATENCIES_MS, LinkSweepView, curve_of
    from arbiter_tui.commands.compare import Sweep, run_sweep, sweep_body
    from arbiter_tui.session.compare import AUTONOMOUS

    setup = Sweep(["square"], list(AUTONOMOUS), 0.5, 1.0, [LinkModel(ms / 1e3) for ms in SWEEP_LATENCIES_MS])
    curve = curve_of(sweep_body(setup, run_sweep(setup)), "square")
    app = still_app(store=seeded_store(latency_ms=lambda i: 40.0 + (i % 20) * 5.0))  # p95: 135 ms

    def swept(pilot) -> None:
        show_frame(pilot.app, link_sweep=LinkSweepView(READY, "square", curve, None))

    assert snap_compare(app, terminal_size=(130, 36), press=["2"], run_before=swept)


def test_an_observed_run_beside_driven_ones(snap_compare):
    """A robot-side controller's run (observe mode, analytics/observe.py), graded in the same table as the
    console's own: 'nav2_rpp' to a goal, from odometry, its command and its plan (synthetic, fixed)."""
    from arbiter_tui.analytics.observe import ObserveConfig, Observer

    store = seeded_store()
    store.start_collection()
    obs = Observer(store, ObserveConfig(label="nav2_rpp"))
    t0 = 1_800_000_100_000_000_000
    obs.on_odometry(t0, 0.0, 0.0, 0.0, 0.0, 0.0)
    obs.on_plan(t0 + 1, [(0.1 * k, 0.05 * k) for k in range(21)])  # to (2.0, 1.0)
    for k in range(1, 60):  # 6 s at 10 Hz along the plan, a little off it, then stopped at the goal
        x = min(2.0, 0.034 * k)
        v = 0.0 if x >= 2.0 else 0.38
        obs.on_command(t0 + k * 100_000_000 - 1, v, 0.0)
        obs.on_odometry(t0 + k * 100_000_000, x, 0.5 * x + 0.03 * math.sin(k / 5), 0.46, v, 0.0)
    store.stop_collection()
    app = still_app(store=store)
    assert snap_compare(app, terminal_size=(100, 30), press=["2"])
