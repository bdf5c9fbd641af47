"""The link's subscription registry: one server subscription per topic, listeners that never remove
each other, each throttled on our side."""

from typing import Any

import pytest

from arbiter_tui.link.streams import Streams


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


class Timers:
    """``call_later`` whose callbacks run when the test says."""

    def __init__(self, clock: Clock) -> None:
        self.clock = clock
        self.due: list[list[Any]] = []

    def __call__(self, wait: float, fn: Any) -> Any:
        entry = [self.clock.t + wait, fn, False]
        timers = self

        class Handle:
            def cancel(self) -> None:
                entry[2] = True
                timers.due.remove(entry)

        self.due.append(entry)
        return Handle()

    def advance(self, dt: float) -> None:
        self.clock.t += dt
        for entry in sorted(self.due, key=lambda e: e[0]):
            if entry[0] <= self.clock.t and not entry[2]:
                self.due.remove(entry)
                entry[1]()


@pytest.fixture
def wire() -> tuple[Streams, list[dict[str, Any]], dict[str, Any], Timers]:
    frames: list[dict[str, Any]] = []
    attached: dict[str, Any] = {}
    clock = Clock()
    timers = Timers(clock)

    def attach(topic: str, fn: Any) -> None:
        assert topic not in attached, "one dispatcher per topic"
        attached[topic] = fn

    def detach(topic: str, fn: Any) -> None:
        assert attached.pop(topic) is fn

    streams = Streams(frames.append, attach, detach, clock=clock, call_later=timers)
    streams.connected()
    return streams, frames, attached, timers


def test_removing_one_listener_leaves_the_others_of_the_same_topic(wire):
    streams, frames, attached, timers = wire
    odom: list[Any] = []
    echo: list[Any] = []
    streams.listen("/odom", "nav_msgs/Odometry", odom.append, 50, 1)
    remove_echo = streams.listen("/odom", "nav_msgs/Odometry", echo.append, 500, 1)
    attached["/odom"]({"n": 1})
    assert odom == [{"n": 1}] and echo == [{"n": 1}]
    remove_echo()
    remove_echo()  # twice: harmless
    timers.advance(0.1)
    attached["/odom"]({"n": 2})
    assert odom == [{"n": 1}, {"n": 2}]
    assert echo == [{"n": 1}]
    assert [f["op"] for f in frames] == ["subscribe"], "the server subscription stays while one listens"
    assert streams.subscriptions()["/odom"][3] == 1


def test_one_server_subscription_per_topic_with_the_loosest_parameters(wire):
    streams, frames, _, _ = wire
    remove_slow = streams.listen("/latency_report", "std_msgs/String", lambda m: None, 500, 1)
    remove_all = streams.listen("/latency_report", "std_msgs/String", lambda m: None, 0, 10)
    subscribes = [f for f in frames if f["op"] == "subscribe"]
    assert len({f["id"] for f in subscribes}) == 1, "one server subscription, updated under its id"
    assert (subscribes[0]["throttle_rate"], subscribes[0]["queue_length"]) == (500, 1)
    assert (subscribes[-1]["throttle_rate"], subscribes[-1]["queue_length"]) == (0, 10)
    remove_all()  # back to what the remaining listener needs
    assert (frames[-1]["op"], frames[-1]["throttle_rate"], frames[-1]["queue_length"]) == (
        "subscribe",
        500,
        1,
    )
    remove_slow()
    assert frames[-1] == {"op": "unsubscribe", "id": subscribes[0]["id"], "topic": "/latency_report"}


def test_the_last_listener_gone_detaches_and_a_new_one_subscribes_afresh(wire):
    streams, frames, attached, _ = wire
    remove = streams.listen("/cmd_vel_measured", "geometry_msgs/Twist", lambda m: None, 500, 1)
    remove()
    assert "/cmd_vel_measured" not in attached and streams.subscriptions() == {}
    streams.listen("/cmd_vel_measured", "geometry_msgs/Twist", lambda m: None, 500, 1)
    ids = [f["id"] for f in frames if f["op"] == "subscribe"]
    assert len(ids) == 2 and ids[0] != ids[1]


def test_a_throttled_listener_gets_at_most_one_message_per_interval_and_the_newest_at_its_end(wire):
    streams, _, attached, timers = wire
    got: list[int] = []
    every: list[int] = []
    streams.listen("/odom", "nav_msgs/Odometry", lambda m: every.append(m["n"]), 0, 1)
    streams.listen("/odom", "nav_msgs/Odometry", lambda m: got.append(m["n"]), 500, 1)
    for n in range(10):  # 20 Hz for 0.5 s
        attached["/odom"]({"n": n})
        timers.advance(0.05)
    timers.advance(0.01)
    assert every == list(range(10))
    assert got == [0, 9], "the first at once, the newest when the 0.5 s ended"
    timers.advance(2.0)
    assert got == [0, 9], "nothing is delivered twice"


def test_a_removed_listener_gets_no_held_back_message(wire):
    streams, _, attached, timers = wire
    got: list[int] = []
    remove = streams.listen("/odom", "nav_msgs/Odometry", lambda m: got.append(m["n"]), 500, 1)
    attached["/odom"]({"n": 1})
    attached["/odom"]({"n": 2})
    remove()
    timers.advance(1.0)
    assert got == [1]
    assert timers.due == []


def test_nothing_is_sent_while_down_and_everything_again_on_reconnect(wire):
    streams, frames, _, _ = wire
    streams.listen("/odom", "nav_msgs/Odometry", lambda m: None, 50, 1)
    streams.listen("/latency_report", "std_msgs/String", lambda m: None, 0, 10)
    streams.disconnected()
    frames.clear()
    streams.listen("/scan", "sensor_msgs/LaserScan", lambda m: None, 500, 1)
    assert frames == []
    streams.connected()
    assert sorted(f["topic"] for f in frames) == ["/latency_report", "/odom", "/scan"]
    assert all(f["op"] == "subscribe" for f in frames)


def test_a_listener_may_remove_itself_while_called():
    streams = Streams(lambda f: None)
    streams.connected()
    got: list[Any] = []
    removers: list[Any] = []

    def once(msg: Any) -> None:
        got.append(msg)
        removers[0]()

    removers.append(streams.listen("/t", "std_msgs/String", once))
    streams.dispatch("/t", {"data": "a"})
    streams.dispatch("/t", {"data": "b"})
    assert got == [{"data": "a"}]


def test_negative_parameters_are_refused():
    with pytest.raises(ValueError):
        Streams(lambda f: None).listen("/t", "std_msgs/String", lambda m: None, throttle_ms=-1)


def test_a_new_listener_never_deadlocks_with_a_message_being_dispatched():
    """roslibpy's emitter holds its lock while it calls our dispatcher (which takes ours); listening to a
    new topic takes the emitter's lock to attach. Attaching under our lock deadlocked the UI thread
    (selecting a row on screen 4) against the reactor (odometry arriving): both hung."""
    import threading

    from roslibpy.event_emitter import EventEmitterMixin

    emitter = EventEmitterMixin()
    in_attach, emitting = threading.Event(), threading.Event()

    def attach(topic: str, fn: Any) -> None:
        if topic == "/scan":  # the second listener: hold here until a dispatch is under way
            in_attach.set()
            emitting.wait(5)
        emitter.on(topic, fn)

    streams = Streams(lambda f: None, attach=attach, detach=emitter.off)
    streams.connected()
    got: list[Any] = []
    streams.listen("/odom", "nav_msgs/Odometry", got.append)
    emitter.on("/odom", lambda msg: emitting.set())  # runs under the emitter's lock, before ours is taken
    ui = threading.Thread(
        target=streams.listen, args=("/scan", "sensor_msgs/LaserScan", got.append), daemon=True
    )
    reactor = threading.Thread(
        target=lambda: (in_attach.wait(5), emitter.emit("/odom", {"n": 1})), daemon=True
    )
    ui.start()
    reactor.start()
    ui.join(5)
    reactor.join(5)
    assert not ui.is_alive() and not reactor.is_alive(), "deadlocked"
    assert got == [{"n": 1}]
