"""What a robot announces (arbiter_backend.fleet.Announcer), read from the backend's own state: who drives,
the run grades, the rates, the history. No Zenoh: the clocks and the backend's parts are real or passed in."""

import asyncio
import json
import time
import types

import pytest

from arbiter_backend.autonomy import AutonomyService
from arbiter_backend.fleet import Announcer, FleetSettings, RobotStop, Sources
from arbiter_backend.topicwatch import TopicWatch
from arbiter_backend.tracker import LatencyTracker
from arbiter_core import envelope, fleet, stopping
from arbiter_core.kinematics import Pose
from arbiter_core.mission import Mission, Phase
from arbiter_core.timesync import TimeSync
from arbiter_core.topicstats import Expectation

W = 1_800_000_000.0


class Clock:
    def __init__(self, t=100.0):
        self.t = t

    def __call__(self):
        return self.t


class Sync:
    def cached(self):
        return TimeSync("chrony", True, 0.1, 0.35)


def make(autonomy=False, expect=()):
    mono = Clock()
    tracker = LatencyTracker(monotonic=mono, clock_ns=lambda: int(W * 1e9))
    watch = TopicWatch(clock=mono)
    svc = AutonomyService(lambda key, msg: None, lambda v, w: None, lambda: {"sec": 0, "nanosec": 0})
    odom = {
        "pose": {"pose": {"position": {"x": 1.0, "y": 2.0}, "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}},
        "twist": {"twist": {"linear": {"x": 0.25}, "angular": {"z": -0.5}}},
    }
    src = Sources(
        tracker=tracker,
        watch=watch,
        autonomy=svc if autonomy else None,
        odometry=lambda: odom,
        cmd_topic="/cmd_vel",
        namespace="/lab/r1",
        mode="embedded, sim",
        token=False,
        secure=True,
        host="lab-r1",
        bridge_port=9090,
        api_port=8085,
    )
    settings = FleetSettings(("tcp/127.0.0.1:7447",), "r1", expect=tuple(expect))
    return Announcer(settings, src, W - 60, Sync()), mono, tracker, watch, svc


def test_status_says_where_to_open_the_robot_and_its_pose():
    a, mono, *_ = make()
    s = a.status(mono(), W)
    assert (s.rosbridge, s.tracker, s.namespace) == ("wss://lab-r1:9090", "https://lab-r1:8085", "/lab/r1")
    assert (s.pose, s.velocity, s.driver, s.lease_ms) == ((1.0, 2.0, 0.0), (0.25, -0.5), "nobody", 1500)
    fleet.encode(s)


def test_who_drives_console_then_a_foreign_controller_then_nobody():
    a, mono, tracker, watch, _ = make()
    assert a.driver(mono(), W) == ("nobody", None)
    tracker.on_stamped(envelope.build(0.2, 0.0, seq=1, clock_ns=lambda: int(W * 1e9)), int(W * 1e9))
    mono.t += 0.3
    driver, detail = a.driver(mono(), W)
    assert driver == "console" and detail == "last command 300 ms ago"
    mono.t += 2.0  # the console stopped; Nav2 drives on /cmd_vel
    watch.watch("/cmd_vel", "geometry_msgs/msg/Twist")
    for i in range(20):
        watch.note("/cmd_vel", 48, at=mono.t - 1.0 + i * 0.05)
    a.status(mono(), W)  # the status reads the topic figures
    assert a.driver(mono(), W) == ("foreign", "commands on /cmd_vel at 20 Hz")
    mono.t += 3.0
    a.status(mono(), W)
    assert a.driver(mono(), W) == ("nobody", "last command 5 s ago")


def test_a_robot_side_run_drives_then_is_graded_once_and_counted():
    a, mono, _, _, svc = make(autonomy=True)
    m = Mission.named("square", "pure_pursuit", Pose(0, 0, 0), now_ms=W * 1e3)
    svc.autonomy.mission = m
    assert a.driver(mono(), W + 1) == ("robot", "pure_pursuit on square")
    s = a.status(mono(), W + 1)
    assert (s.controller, s.mission, s.run_state, s.waypoint, s.waypoints) == (
        "pure_pursuit",
        "square",
        "running",
        0,
        4,
    )
    svc.autonomy.mission = m.ended(Phase.COMPLETED, W * 1e3 + 41_250)
    svc.autonomy.final_error_m = 0.0812
    out = a.due(mono(), W + 42)
    runs = [p for p in out if p.kind == "runs"]
    assert len(runs) == 1 and runs[0].count == 1
    assert runs[0].last.words() == "completed 41.2 s, 0.08 m"
    mono.t += 10
    assert not [p for p in a.due(mono(), W + 52) if p.kind == "runs"]  # graded once
    assert a.status(mono(), W + 52).runs == 1


def test_runs_within_the_gap_are_sent_once_with_both_counted():
    a, mono, _, _, svc = make(autonomy=True)
    for i, t in enumerate((W, W + 1)):
        svc.autonomy.mission = Mission.named("corner", "stanley", Pose(0, 0, 0), t * 1e3).ended(
            Phase.ABORTED, t * 1e3 + 500
        )
        sent = [p for p in a.due(mono(), t + 1) if p.kind == "runs"]
        assert len(sent) == (1 if i == 0 else 0)
        mono.t += 1.0
    mono.t += fleet.RUNS_MIN_GAP_S
    sent = [p for p in a.due(mono(), W + 9) if p.kind == "runs"]
    assert len(sent) == 1 and sent[0].count == 2 and sent[0].last.n == 2


def test_each_payload_at_its_period():
    a, mono, *_ = make()
    kinds = []
    for _ in range(int(10 / 0.25)):  # ten seconds of the announcer's beat
        kinds += [p.kind for p in a.due(mono(), W + mono.t)]
        mono.t += 0.25
    assert (kinds.count("status"), kinds.count("latency"), kinds.count("topics")) == (10, 5, 2)


def test_topics_are_judged_against_the_robots_expectations():
    a, mono, _, watch, _ = make(expect=[Expectation("/scan", 9.5)])
    watch.watch("/odom", "nav_msgs/msg/Odometry")
    for i in range(100):
        watch.note("/odom", 700, at=mono.t - 2.0 + i * 0.02)
    a.status(mono(), W)
    t = a.topics(W)
    assert [(x.name, x.health) for x in t.topics] == [("/scan", "missing"), ("/odom", "ok")]


def test_latency_summary_and_the_hosts_clock():
    a, _mono, tracker, _, _ = make()
    for i in range(1, 101):
        sent = int((W - i / 1000) * 1e9)  # latency i ms
        tracker.on_stamped(envelope.build(0.1, 0.0, seq=i, clock_ns=lambda s=sent: s), int(W * 1e9))
    lat = a.latency(W)
    assert (lat.count, lat.total) == (100, 100)
    assert (lat.p50_ms, lat.p95_ms, lat.max_ms) == pytest.approx((51.0, 96.0, 100.0), abs=0.01)
    assert (lat.sync_source, lat.sync_ok, lat.sync_error_ms) == ("chrony", True, 0.35)


def test_history_thins_the_status_and_keeps_what_fits():
    a, mono, *_ = make()
    for _ in range(int(120 / 0.25)):  # two minutes
        a.due(mono(), W + mono.t - 100)
        mono.t += 0.25
    answer = json.loads(a.history(10.0, W + mono.t - 100))
    kinds = [e["kind"] for e in answer["entries"]]
    assert kinds.count("status") == 12  # one every 10 s, not 120
    assert kinds.count("latency") == 60 and kinds.count("topics") == 4
    last_minute = json.loads(a.history(1.0, W + mono.t - 100))
    assert 0 < len(last_minute["entries"]) < len(answer["entries"])
    assert fleet.decode(a.history(10.0, W + mono.t - 100), "history", "r1").minutes == 10.0


# -- the stop a fleet console asks for, done in the robot's backend (arbiter_backend.fleet.RobotStop) -----
class SlowCancel:
    """An action server's cancel service, provided by a bridge client, that answers after ``delay``."""

    def __init__(self, delay):
        self.delay, self.answered = delay, asyncio.Event()

    async def call(self, args, timeout):
        await asyncio.sleep(min(self.delay, timeout))
        self.answered.set()
        return True, {"return_code": 0, "goals_canceling": [{"goal_id": {}}]}


class Room:
    def __init__(self, provided):
        self.provided, self.graph = provided, None


class Robot:
    """The backend as RobotStop uses it: its zero, its endpoint's provided services, its bus."""

    def __init__(self, provided=None):
        self.done: list[str] = []
        self.endpoint = types.SimpleNamespace(service_room=Room(provided or {}))
        self.bus = types.SimpleNamespace(type_of=lambda topic: "geometry_msgs/msg/Twist", publish=self.zero)

    def publish_zero(self):
        self.done.append("zero")

    def zero(self, topic, msg):
        self.done.append(f"zero on {topic}")


def test_a_fleet_stop_sends_its_zero_first_and_answers_when_a_step_fails():
    a, *_ = make(autonomy=True)
    robot = Robot()

    def broken():
        robot.done.append("abort")
        raise RuntimeError("the run's state is torn")

    a.src.autonomy.stop = broken

    async def run():
        return await RobotStop(robot, a, asyncio.get_running_loop()).stop()

    answer = asyncio.run(run())
    assert robot.done == ["zero", "abort"]
    assert answer.zero and answer.aborted is None
    assert answer.words() == "stopped: nothing was driving, zero sent"


def test_a_fleet_stop_sees_who_drives_now_and_answers_in_time_with_a_slow_cancel_pending():
    a, mono, _, watch, _ = make()
    a.status(mono(), W)  # the announcer's figures: nothing on /cmd_vel yet
    watch.watch("/cmd_vel", "geometry_msgs/msg/Twist")  # then a foreign controller drives
    for i in range(20):
        watch.note("/cmd_vel", 48, at=mono.t - 1.0 + i * 0.05)
    slow = SlowCancel(stopping.CANCEL_TIMEOUT_S * 0.9)
    robot = Robot({"/lab/r1/follow_path" + stopping.CANCEL_SUFFIX: slow})  # under its namespace

    async def run():
        stop = RobotStop(robot, a, asyncio.get_running_loop())
        t0 = time.monotonic()
        answer = await stop.stop()
        took = time.monotonic() - t0
        await asyncio.wait_for(slow.answered.wait(), 5)  # the pending cancel goes on after the answer
        stop.close()  # the backend stops: the zeros still under way end
        await asyncio.sleep(0)
        return answer, took, stop

    answer, took, stop = asyncio.run(run())
    assert took < fleet.STOP_TIMEOUT_S, took
    assert answer.driver == "foreign"
    assert answer.cancels == (fleet.StopCancel("/lab/r1/follow_path", "pending"),)
    assert answer.words().startswith("asked: /lab/r1/follow_path cancel pending, zero sent")
    assert robot.done[0] == "zero" and "zero on /cmd_vel" in robot.done
    assert all(t.done() for t in stop._tasks)
