"""Screen 4, topics: snapshots at 80x24 and 100x30 with fixed figures, and the keys a user presses."""

from dataclasses import replace

import pytest

from arbiter_core.topicstats import NOT_INSTALLED, TopicFigures
from arbiter_tui.latency.topics_client import TopicsState
from arbiter_tui.shell.widgets.topics import RatePlot, TopicDetail, TopicsList

from ..support.tui import burst, still_app, until

TOPICS = (
    TopicFigures("/camera/image_raw", "sensor_msgs/msg/Image", "ok", 1, 1, 75, 900, 15.0, 62.1, 71.0, 2.2,
                 15.7e6, 1_049_112.0, True, 3.1, 4.0, 12.0, 15.0),
    TopicFigures("/cmd_vel", "geometry_msgs/msg/Twist", "waiting", 0, 1),
    TopicFigures("/imu/data", "sensor_msgs/msg/Imu", "unmeasured", 1, 0, note=NOT_INSTALLED),
    TopicFigures("/odom", "nav_msgs/msg/Odometry", "ok", 1, 2, 250, 3000, 50.0, 19.1, 21.0, 0.3, 35_400.0,
                 708.0, True, 20.2, 20.3, 8.0, 50.0),
    TopicFigures("/rosout", "rcl_interfaces/msg/Log", "ok", 4, 0, 3, 40, 0.6, 100.0, 2600.0, 900.0, 120.0,
                 200.0, False, None, None, 900.0, None),
    TopicFigures("/scan", "sensor_msgs/msg/LaserScan", "slow", 1, 1, 22, 800, 4.3, 98.0, 260.0, 40.0,
                 6_400.0, 1_496.0, True, 1.2, 2.5, 230.0, 10.0, qos_note="a reliable subscriber cannot "
                 "match a best-effort publisher"),
    TopicFigures("/tf", "tf2_msgs/msg/TFMessage", "silent", 2, 3, 0, 1200, age_ms=12_400.0,
                 usual_rate_hz=100.0),
)  # fmt: skip
QUIET = TopicFigures("/stamped_cmd_vel", "std_msgs/msg/String", "quiet", 1, 1, 0, 240)  # commands, then none
# the last minute as the backend sampled it (once a second): each topic at its rate, then half of it
TOPICS = tuple(
    replace(t, rate_history=tuple((t.rate_hz or 0.0) * (1.0 if i < 40 else 0.5) for i in range(60)))
    for t in TOPICS
)
STATE = TopicsState(polls=60, window_s=5.0, topics=TOPICS)


def topics_app(state: TopicsState = STATE):
    app = still_app()
    app.sampler.topics_polled(state)
    return app


@pytest.mark.parametrize("size", [(100, 30), (80, 24)], ids=["100x30", "80x24"])
def test_topics_screen(snap_compare, size):
    assert snap_compare(topics_app(), terminal_size=size, press=["4", "down", "down", "down"])


def test_topics_screen_before_the_first_answer_and_when_the_backend_is_down(snap_compare):
    down = TopicsState(polls=3, error="cannot connect (ConnectError: All connection attempts failed)")
    assert snap_compare(topics_app(down), terminal_size=(80, 24), press=["4"])


async def test_filter_sort_and_select_with_the_keys_a_user_presses():
    app = topics_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("4")
        table = app.screen.query_one(TopicsList)
        detail = app.screen.query_one(TopicDetail)
        assert [t.name for t in table.rows()][:2] == ["/camera/image_raw", "/cmd_vel"]
        assert table.selected == "/camera/image_raw" and table.has_focus
        # s: by rate (busiest first), s again: by bandwidth
        await pilot.press("s")
        assert table.sort == "rate" and [t.name for t in table.rows()][:2] == ["/odom", "/camera/image_raw"]
        await pilot.press("s")
        assert table.rows()[0].name == "/camera/image_raw"
        await pilot.press("r")  # reversed: the quietest first
        assert table.rows()[-1].name == "/camera/image_raw"
        # / then type: only the sensor topics, the selection moves into what is left
        await pilot.press("slash", *"sensor")
        assert {t.name for t in table.rows()} == {"/camera/image_raw", "/imu/data", "/scan"}
        await pilot.press("escape", "home", "down")
        assert table.has_focus
        selected = table.selected
        assert selected in {"/imu/data", "/camera/image_raw", "/scan"}
        await pilot.pause()
        assert selected in str(detail.render())
        assert app.screen.query_one(RatePlot).selected == selected
        # the detail of the slow topic names the QoS mismatch
        table.selected = "/scan"
        await pilot.pause()
        text = str(detail.render())
        assert "QoS: a reliable subscriber cannot match a best-effort publisher" in text
        assert "rate 4.30 Hz" in text and "usual 10.0 Hz" in text
        # a new answer without the selected topic: the selection moves to the first row
        app.sampler.topics_polled(TopicsState(polls=61, window_s=5.0, topics=TOPICS[:2]))
        app.refresh_frame(force=True)
        await pilot.pause()
        assert table.selected in {"/camera/image_raw", "/cmd_vel"}
        # teleop keys do nothing here, and 1 goes back to driving
        await pilot.press("escape", "1")
        assert app.current_mode == "control"


async def test_keys_typed_at_once_on_the_first_visit_go_to_the_table_not_the_filter():
    """4 and 1 typed at once on the first visit: back on the control screen (the 1 used to be swallowed).
    A burst after 4 reaches the table (s sorts, down selects), and nothing lands in the filter until /
    opens it; esc and enter give the keys back to the table."""
    from textual.widgets import Input

    first = topics_app()
    async with first.run_test(size=(120, 36)) as pilot:
        await pilot.pause()
        burst(first, "4", "1", "a")  # a: the next algorithm, on the control screen
        assert await until(pilot, lambda: first.session.loop.algorithm == "go_to_goal")
        assert first.current_mode == "control"
    app = topics_app()
    async with app.run_test(size=(120, 36)) as pilot:
        await pilot.pause()
        burst(app, "4", "s", "down", "o", "d", "o", "m")

        def sorted_by_rate() -> bool:
            return app.current_mode == "topics" and app.screen.query_one(TopicsList).sort == "rate"

        assert await until(pilot, sorted_by_rate)
        await pilot.pause()
        table, field = app.screen.query_one(TopicsList), app.screen.query_one("#topics-filter", Input)
        assert table.has_focus and field.value == ""
        assert table.selected == "/camera/image_raw"  # the busiest is /odom, then one down
        # / opens the filter: what follows is typed into it
        burst(app, "slash", "o", "d", "o", "m")
        assert await until(pilot, lambda: field.value == "odom")
        assert field.has_focus and [t.name for t in table.rows()] == ["/odom"]
        burst(app, "escape", "s")  # back to the table: s sorts again (by bandwidth), not typed
        assert await until(pilot, lambda: table.sort == "bandwidth")
        assert table.has_focus and field.value == "odom"
        burst(app, "slash", "backspace", "backspace", "left", "delete", "backspace", "enter", "r")
        assert await until(pilot, lambda: table.reverse)
        assert table.has_focus and field.value == ""
        # tab does not wander into the filter either: only / (or a click) opens it
        await pilot.press("tab")
        assert not field.has_focus
        await pilot.click("#topics-filter")
        assert field.has_focus
        await pilot.press("escape")
        assert table.has_focus
    again = topics_app()  # / typed right behind 4, as the screen first opens: the filter opens
    async with again.run_test(size=(120, 36)) as pilot:
        await pilot.pause()
        burst(again, "4", "slash")

        def filter_open() -> bool:
            return again.current_mode == "topics" and isinstance(again.focused, Input)

        assert await until(pilot, filter_open)


async def test_client_side_simulation_says_there_is_no_backend_to_ask_not_waiting_for_one():
    """--sim: no backend, so no /api/topics; the screen says so instead of waiting for it forever."""
    app = still_app(mode="sim")
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("4")
        table, detail = app.screen.query_one(TopicsList), app.screen.query_one(TopicDetail)
        assert await until(pilot, lambda: "no backend" in table.render().plain)
        text = table.render().plain
        assert "client-side simulation" in text and "waiting" not in text
        assert "select a topic" not in str(detail.render())  # there is none to select


async def test_the_header_marks_the_sorted_column_and_the_footer_lists_every_key_within_80_columns():
    from textual.widgets._footer import FooterKey

    app = topics_app()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("4")
        table = app.screen.query_one(TopicsList)

        def header() -> list[str]:
            return table.render().plain.splitlines()[0].split()

        assert header()[:2] == ["topic", "▲"]  # names A to Z
        await pilot.press("s")  # by rate: the busiest first
        await pilot.pause()
        words = header()
        assert words[words.index("Hz") + 1] == "▼" and words.count("▼") + words.count("▲") == 1
        await pilot.press("r")  # reversed: the quietest first
        await pilot.pause()
        words = header()
        assert words[words.index("Hz") + 1] == "▲" and "▼" not in words
        await pilot.press("s", "s", "s")  # bandwidth, delay, age (still reversed: the youngest first)
        await pilot.pause()
        words = header()
        assert words[words.index("age") + 1] == "▲"
        # the footer names r (what it does: reverse the order) and every key fits in 80 columns
        keys = {k.key: k for k in app.screen.query(FooterKey)}
        assert {"slash", "s", "r"} <= set(keys) and keys["r"].description == "Flip"
        assert all(k.region.right <= 80 and k.region.width > 0 for k in keys.values())
        assert max(k.region.right for k in keys.values()) == keys["question_mark"].region.right


async def test_a_quiet_command_topic_is_dim_and_explained_a_stopped_sensor_is_red():
    app = topics_app(replace(STATE, topics=(*TOPICS, QUIET)))
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("4", "end")
        table = app.screen.query_one(TopicsList)
        detail = app.screen.query_one(TopicDetail)

        def row_style(name: str) -> str:
            text = table.render()
            start = text.plain.index(name)
            return " ".join(str(s.style) for s in text.spans if s.start <= start < s.end)

        assert table.selected == "/tf"
        table.selected = "/stamped_cmd_vel"
        await pilot.pause()
        quiet = row_style("/stamped_cmd_vel")
        assert "dim" in quiet and "red" not in quiet
        line = next(x for x in table.render().plain.splitlines() if x.startswith("/stamped_cmd_vel"))
        assert line.split()[2] == "quiet"
        assert "not a fault" in str(detail.render())
        table.selected = "/scan"
        await pilot.pause()
        assert "red" in row_style("/tf") and "SILENT" in table.render().plain


async def test_while_the_backends_monitor_restarts_no_topic_is_silent_the_screen_says_why():
    why = "monitor restarted: MessageError: invalid message type name 'std_srvs/srv/Trigger_Event'"
    held = tuple(t if t.state == "unmeasured" else replace(t, state="unknown", note=why) for t in TOPICS)
    app = topics_app(replace(STATE, topics=held, interrupted=why))
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("4", "end")
        table = app.screen.query_one(TopicsList)
        detail = app.screen.query_one(TopicDetail)
        assert table.selected == "/tf"
        await pilot.pause()
        plain = table.render().plain
        assert "SILENT" not in plain
        assert next(x for x in plain.splitlines() if x.startswith("/tf")).split()[2] == "unknown"
        assert f"state unknown ({why})" in str(detail.render())
        table.selected = "/imu/data"  # cannot be read at all: its own reason, and the monitor's below
        await pilot.pause()
        text = str(detail.render())
        assert f"state unmeasured ({NOT_INSTALLED})" in text and text.rstrip().endswith(why)


async def test_the_rate_plot_covers_the_last_minute_the_moment_the_screen_opens():
    """The backend samples every topic's rate once a second whoever asks: the first answer the screen gets
    holds the last minute, and the plot draws all of it (from -59 s), not only what came since it opened."""
    app = topics_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("4")
        plot = app.screen.query_one(RatePlot)
        await pilot.pause()
        assert plot.selected == "/camera/image_raw" and plot.draws >= 1
        assert plot._user_x_min <= -59.0 and plot._user_x_max >= 0.0
        x = plot._datasets[0].x
        assert len(x) == 60 and x[0] == -59.0 and x[-1] == 0.0
        assert app.frame.topics.rates("/camera/image_raw")[:2] == (15.0, 15.0)


def test_a_late_message_of_the_last_topic_never_takes_the_new_topics_echo():
    """The link's thread may deliver one more message of a topic after its echo was removed (it was under
    way): it must not overwrite the echo of the topic now selected, which would then never show. (The
    check and the swap are one step under a lock, so the race between them is closed too; this test
    pins the rule, sequentially.)"""
    from arbiter_tui.link.base import Telemetry

    class EchoLink:
        state = "CONNECTED"

        def __init__(self) -> None:
            self.telemetry = Telemetry()
            self.echoes: dict[str, object] = {}

        def send(self, v: float, w: float) -> bool:
            return True

        def close(self) -> None:
            pass

        def echo(self, topic, type_name, callback):
            self.echoes[topic] = callback
            return lambda: None

    link = EchoLink()
    app = still_app(link=link)
    figures = {t.name: t for t in STATE.topics}
    app.session.echo_topic(figures["/odom"])
    app.session.echo_topic(figures["/scan"])  # the user moved on
    link.echoes["/odom"]({"header": {"frame_id": "odom"}})  # /odom's last message, late
    assert app.session.echo.current == ("/scan", "waiting for a message ...")
    link.echoes["/scan"]({"ranges": [1.0]})
    assert app.session.echo.current[0] == "/scan" and "ranges" in app.session.echo.current[1]


async def test_showing_the_topics_screen_forces_one_frame_not_two():
    """Textual calls every class's on_screen_resume in the MRO: the topics screen's own must not call
    BaseScreen's again (it did: two forced frames per showing, the dearest kind)."""
    from ..support.tui import still_app

    app = still_app()
    forced = []
    real = app.refresh_frame

    def counting(force: bool = False) -> None:
        forced.append(force)
        real(force)

    app.refresh_frame = counting
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.press("4")
        await pilot.pause()
        forced.clear()
        await pilot.press("1", "4")
        await pilot.pause()
        assert forced.count(True) == 2  # one as screen 1 comes back, one as screen 4 does
