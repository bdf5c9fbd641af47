"""The backend's topic monitor (``arbiter_backend.topicwatch``) on the embedded bus, on a fake clock."""

from arbiter_backend.bus import TopicBus
from arbiter_backend.topicwatch import EmbeddedTopics, TopicFilter, TopicWatch
from arbiter_core.topicstats import NOT_INSTALLED


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def state(topics: EmbeddedTopics, name: str) -> str:
    return next(t["state"] for t in topics.answer()["topics"] if t["name"] == name)


def test_a_topic_declared_at_start_that_waits_for_commands_is_quiet_after_them_not_silent():
    """The backend declares its command topic before the monitor starts; the monitor watches it from its
    start, so a 10 s hold at 10 Hz that begins half a minute later, then stops, leaves it quiet."""
    clock, bus = Clock(), TopicBus()
    bus.declare("/stamped_cmd_vel", "std_msgs/String")
    topics = EmbeddedTopics(bus, TopicWatch(clock=clock))
    for i in range(100):
        clock.now = 30.0 + i / 10
        bus.publish("/stamped_cmd_vel", {"data": "held"})
    clock.now = 41.5
    assert state(topics, "/stamped_cmd_vel") == "ok"  # still in the window
    clock.now = 46.0
    assert state(topics, "/stamped_cmd_vel") == "quiet"
    # the same on a topic first seen with its first message: steady since it appeared, so silent
    bus.declare("/scan", "std_msgs/String")
    for i in range(100):
        clock.now = 50.0 + i / 10
        bus.publish("/scan", {"data": "scan"})
    clock.now = 61.5
    assert state(topics, "/scan") == "silent"


def test_the_backend_samples_each_topics_rate_once_a_second_whether_or_not_anyone_asks():
    clock, bus = Clock(), TopicBus()
    bus.declare("/odom", "std_msgs/String")
    topics = EmbeddedTopics(bus, TopicWatch(clock=clock))
    for i in range(1, 90 * 50 + 1):  # 50 Hz for 90 s; the backend's beat (tick) four times a second
        clock.now = i / 50
        bus.publish("/odom", {"data": "odom"})
        if i % 12 == 0:
            topics.tick()
    odom = next(t for t in topics.answer()["topics"] if t["name"] == "/odom")  # the first answer
    history = odom["rate_history"]
    assert len(history) == 60 and all(abs(r - 50.0) < 0.01 for r in history)
    bus.declare("/late", "std_msgs/String")  # declared later: watched from the next beat
    topics.tick()
    clock.now += 3.0
    topics.tick()
    late = next(t for t in topics.answer()["topics"] if t["name"] == "/late")
    assert late["state"] == "waiting" and late["rate_history"] == [None] * 4


def test_hidden_topics_of_services_and_actions_are_taken_unless_excluded():
    hidden = ("/nav/_action/feedback", "/nav/_action/status", "/srv/_service_event")
    every = TopicFilter.parse(None, None)
    assert all(every.wants(t) for t in (*hidden, "/odom"))
    visible = TopicFilter.parse(None, "*/_*")
    assert not any(visible.wants(t) for t in hidden) and visible.wants("/odom")


def test_a_held_watch_says_why_and_its_topics_are_unknown_until_released():
    clock = [100.0]
    watch = TopicWatch(window_s=1.0, clock=lambda: clock[0])
    watch.watch("/odom", "nav_msgs/msg/Odometry")
    watch.watch("/imu", "sensor_msgs/msg/Imu", unmeasured=NOT_INSTALLED)
    for i in range(200):  # steady at 50 Hz for 4 s, then nothing for 2 s: silent
        watch.note("/odom", 10, at=94.0 + i / 50)
    states = {t["name"]: t["state"] for t in watch.answer()["topics"]}
    assert states == {"/odom": "silent", "/imu": "unmeasured"} and watch.answer()["interrupted"] is None
    watch.hold("topic-monitor", "monitor restarted: OSError: x")
    answer = watch.answer()
    assert answer["interrupted"] == "monitor restarted: OSError: x"
    assert {t["name"]: (t["state"], t["note"]) for t in answer["topics"]} == {
        "/odom": ("unknown", "monitor restarted: OSError: x"),
        "/imu": ("unmeasured", NOT_INSTALLED),
    }
    watch.release("topic-monitor")
    assert {t["name"]: t["state"] for t in watch.answer()["topics"]}["/odom"] == "silent"
