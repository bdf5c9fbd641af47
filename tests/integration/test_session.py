"""The robot session without Textual: a mission driven through the real embedded backend (rosbridge
endpoint, tracker, simulator in their own process) by the real roslibpy link, the session's own thread
keeping time; and a paint that takes 300 ms does not delay a command."""

import time

from rich.text import Text
from textual.widget import Widget

from arbiter_tui.analytics.runs import COMPLETED
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED, Telemetry
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session import schedule
from arbiter_tui.session.collector import TickCollector
from arbiter_tui.session.robot import MissionFinished, RobotSession
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell.app import make_app

from ..support.backend import get_json, start_backend
from ..support.waits import async_until, wait_for


def test_a_mission_through_the_real_backend_with_no_textual(tmp_path):
    backend = start_backend()
    link = RosLink("127.0.0.1", backend.bridge_port)
    session = RobotSession(Settings(export_dir=tmp_path), link)
    events = []
    session.on_event = events.append
    try:
        assert wait_for(lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, timeout=15)
        session.start()
        session.select_algorithm("go_to_goal")
        assert session.go() is None
        assert wait_for(lambda: not session.loop.running, timeout=60)
        (run,) = session.store.runs()
        assert run.outcome == COMPLETED and run.mission == "square" and run.stats.sampleCount > 100
        assert events == [MissionFinished("go_to_goal", "square")]
        health = get_json(f"{backend.api}/api/health")
        assert health["total_seen"] >= run.stats.sampleCount  # every command went through the tracker
        (csv,) = session.export("csv")
        assert csv.path is not None and csv.path.exists()
    finally:
        session.close()
        link.close()
        backend.stop()


class Timed:
    """A link that notes when each command went out (the wire is not what is measured here)."""

    def __init__(self):
        self.telemetry = Telemetry()
        self.state = CONNECTED
        self.at: list[float] = []

    def send(self, v, w):
        self.at.append(time.monotonic())
        return True

    def close(self):
        pass


class SlowPaint(Widget):
    """A widget whose every paint takes 300 ms of the UI thread."""

    def render(self) -> Text:
        time.sleep(0.3)
        return Text("slow")

    def on_mount(self) -> None:
        self.set_interval(0.05, self.refresh)


async def test_a_slow_paint_does_not_delay_the_commands(tmp_path):
    link = Timed()
    settings = Settings(mode="embedded", handle_signals=False, export_dir=tmp_path, repeat_rate=10.0)
    app = make_app(settings, link, TrackerClient("http://127.0.0.1:9"))
    async with app.run_test(size=(100, 30)) as pilot:
        app.session.select_algorithm("go_to_goal")
        assert app.session.go() is None
        await app.screen.mount(SlowPaint())
        start = len(link.at)
        # thirty commands' worth of painting 300 ms frames (about 3 s when nothing is late)
        assert await async_until(lambda: len(link.at) >= start + 30, timeout=15)
        gaps = [b - a for a, b in zip(link.at[start:], link.at[start + 1 :], strict=False)]
        await pilot.press("space")
    assert len(gaps) >= 20
    assert max(gaps) < 0.25, f"a command waited {max(gaps) * 1000:.0f} ms behind a paint"


class LateWrites(Timed):
    """A link whose every command reaches the socket ``late_s`` after it was sent, as a link thread
    starved of CPU by painting writes it (the meter is told the write time, as ``RosLink`` tells it)."""

    def __init__(self, late_s: float):
        super().__init__()
        self.late_s = late_s
        self.seq = 0

    def send(self, v, w):
        self.seq += 1
        now = time.monotonic()
        self.telemetry.meter.on_send(self.seq, time.time() * 1000.0, now + self.late_s)
        return super().send(v, w)


async def test_the_ui_gives_way_when_commands_leave_late(tmp_path):
    """Commands that reach the socket 40 ms late spread the frames out (the UI gives way to the
    robot); frames still come, at least one a second."""
    link = LateWrites(0.04)
    settings = Settings(mode="embedded", handle_signals=False, export_dir=tmp_path, repeat_rate=10.0)
    app = make_app(settings, link, TrackerClient("http://127.0.0.1:9"))
    async with app.run_test(size=(100, 30)) as pilot:
        frames = app.frame_clock
        assert frames is not None
        app.session.select_algorithm("go_to_goal")
        assert app.session.go() is None
        assert await async_until(lambda: frames.frame_s >= frames.SLOWEST_S, timeout=20)
        assert app.session.schedule.tick_late_s >= 0.03
        asked = frames.asked  # ...and frames still come, each drawn before the next is asked for
        assert await async_until(lambda: frames.asked >= asked + 2, timeout=5)
        await pilot.press("space")


def test_a_frame_and_a_collection_wait_until_the_ticks_command_is_on_the_socket(tmp_path, monkeypatch):
    """After a control tick the session thread asks for a frame (``on_tick``: the UI thread wakes) and
    may collect garbage; RosLink writes the command on its reactor's thread. Either one first takes
    the GIL before that thread, and held the command before its stamp or between its stamp and the
    socket (at a Pi-class quota: one-way latency 9-19 ms instead of under 1, in a packet capture)."""
    monkeypatch.setattr(schedule, "WRITE_WAIT_S", 5.0)  # the order is under test, not the bound (a loaded CI)
    backend = start_backend()
    link = RosLink("127.0.0.1", backend.bridge_port)
    session = RobotSession(Settings(export_dir=tmp_path), link)
    handed: list[int] = []  # commands the control loop handed the link
    send = link.send

    def counted(v, w):
        ok = send(v, w)
        if ok:
            handed.append(1)
        return ok

    link.send = counted
    seen: list[tuple[int, int]] = []  # at each collection: (commands written, commands handed over)
    framed: list[tuple[int, int]] = []  # the same, at each frame asked for
    session.schedule.collector = TickCollector(
        period_s=0.2, collect=lambda: seen.append((link.telemetry.meter.sent, len(handed)))
    )
    session.schedule.on_tick = lambda: framed.append((link.telemetry.meter.sent, len(handed)))
    try:
        assert wait_for(lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, timeout=15)
        session.start()
        session.select_algorithm("go_to_goal")
        assert session.go() is None
        assert wait_for(lambda: len([s for s in seen if s[1] >= 2]) >= 8, timeout=30)
        for when in (seen, framed):
            driving = [s for s in list(when) if s[1] >= 2]
            assert len(driving) >= 8 and all(written == handed for written, handed in driving), driving
    finally:
        session.close()
        link.close()
        backend.stop()


def test_a_paint_gives_way_to_a_tick_that_is_due_and_goes_on_once_it_ran(tmp_path):
    """The UI's thread, between widgets of a paint, asks ``give_way``: with the next control tick due
    within the guard it waits until that tick has run, and not otherwise (the session's own thread)."""
    from arbiter_tui.link.sim import SimLink

    session = RobotSession(Settings(export_dir=tmp_path), SimLink())
    guard = 0.02
    try:
        session.start()
        assert wait_for(lambda: session.schedule.ticks_written >= 2, timeout=10)
        far = 0
        for _ in range(30):  # far from the next tick: no wait (a stall between two lines may bring it near)
            assert wait_for(lambda: session.schedule.tick_due_s - time.monotonic() > 3 * guard, timeout=5)
            calls = session.schedule.gave_way
            far += not session.schedule.give_way(guard) and session.schedule.gave_way == calls
            if far == 3:
                break
        assert far == 3
        saw, calls = 0, session.schedule.gave_way
        for _ in range(30):  # close to it: the call returns once the tick has run
            soon = lambda: 0 < session.schedule.tick_due_s - time.monotonic() <= guard / 2  # noqa: E731
            assert wait_for(soon, 5, 0.0005)
            due, seen = session.schedule.tick_due_s, session.schedule.ticks_written
            if session.schedule.give_way(guard):  # False: the tick ran before the call, or ran too late
                saw += 1
                assert session.schedule.ticks_written > seen and time.monotonic() >= due
                if saw == 3:
                    break
        assert saw == 3 and session.schedule.gave_way >= calls + 3
    finally:
        session.close()
    assert not session.schedule.give_way(guard)  # a closed session never holds the UI
