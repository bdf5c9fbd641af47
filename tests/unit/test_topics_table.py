"""The topics screen's rows: filter by words of name or type, sorts, and cell text."""

from arbiter_core.topicstats import TopicFigures
from arbiter_tui.latency.topics_table import cells, detail, headers, select

ROWS = [
    TopicFigures("/odom", "nav_msgs/msg/Odometry", "ok", rate_hz=50.0, bandwidth_bps=30_900.0, age_ms=5.0,
                 stamped=True, delay_mean_ms=0.1, mean_size_bytes=618.0, publishers=1, subscribers=2),
    TopicFigures("/scan", "sensor_msgs/msg/LaserScan", "silent", rate_hz=None, age_ms=9_500.0, total=80),
    TopicFigures("/camera/image", "sensor_msgs/msg/Image", "ok", rate_hz=15.0, bandwidth_bps=15.7e6,
                 age_ms=40.0, stamped=True, delay_mean_ms=3.0),
    TopicFigures("/rosout", "rcl_interfaces/msg/Log", "waiting"),
]  # fmt: skip


def names(rows):
    return [t.name for t in rows]


def test_filter_matches_every_word_in_name_or_type():
    assert names(select(ROWS, "sensor", "name")) == ["/camera/image", "/scan"]
    assert names(select(ROWS, "SENSOR image", "name")) == ["/camera/image"]
    assert names(select(ROWS, "odom", "name")) == ["/odom"]
    assert select(ROWS, "nothing", "name") == []


def test_sorts_put_the_busiest_most_delayed_and_oldest_first():
    assert names(select(ROWS, "", "rate")) == ["/odom", "/camera/image", "/rosout", "/scan"]
    assert names(select(ROWS, "", "bandwidth"))[0] == "/camera/image"
    assert names(select(ROWS, "", "delay"))[:2] == ["/camera/image", "/odom"]
    assert names(select(ROWS, "", "age"))[:2] == ["/rosout", "/scan"]  # never heard from: oldest
    assert names(select(ROWS, "", "name", reverse=True)) == ["/scan", "/rosout", "/odom", "/camera/image"]


def test_cells():
    odom = cells(ROWS[0])
    assert odom[:4] == ("/odom", "nav_msgs/Odometry", "ok", "50.0")
    assert odom[5:] == ("30.9k", "618", "0.1ms", "<0.1s", "1/2")  # a fresh age does not flicker
    assert cells(ROWS[1])[2] == "SILENT" and cells(ROWS[1])[3] == "—"
    assert cells(ROWS[1])[8] == "9.5s"  # nothing in the window: still how long ago its last message came
    assert cells(ROWS[2])[5] == "15.7M"


def test_ages_below_a_tenth_of_a_second_read_fresh_and_older_ones_in_units():
    from arbiter_tui.latency.topics_table import age

    assert [age(v) for v in (None, 3.0, 99.9, 230.0, 1500.0, 42_000.0)] == [
        "—", "<0.1s", "<0.1s", "230ms", "1.5s", "42s",
    ]  # fmt: skip


def test_the_detail_shows_an_absent_figure_as_a_dash_with_no_unit_as_the_table_does():
    never = detail(ROWS[3], 5.0)  # waiting: nothing measured
    assert "bandwidth —  mean size —" in never
    assert "rate — (0 msgs in the last 5 s, 0 in all)" in never
    assert "no message yet" in never
    assert "last message 9.5s ago" in detail(ROWS[1], 5.0)  # silent longer than the window
    assert cells(ROWS[3])[3:7] == ("—", "—", "—", "—")
    measured = detail(ROWS[0], 5.0)
    assert "bandwidth 30.9kB/s  mean size 618B" in measured


def test_the_header_marks_the_sorted_column_with_the_order_shown():
    assert headers("name")[0] == "topic ▲" and headers("name", reverse=True)[0] == "topic ▼"
    assert headers("rate")[3] == "Hz ▼" and headers("rate", reverse=True)[3] == "Hz ▲"
    assert headers("bandwidth")[5] == "B/s ▼" and headers("delay")[7] == "delay ▼"
    assert headers("age")[8] == "age ▼"
    for sort in ("name", "rate", "bandwidth", "delay", "age"):
        assert sum(("▼" in h) + ("▲" in h) for h in headers(sort)) == 1
