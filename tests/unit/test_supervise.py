"""The backend's supervisor (arbiter_backend.supervise): backoff, giving up, injected faults, the state
``/api/health`` lists, and the topic monitor's figures while it restarts (real threads and tasks)."""

import asyncio
import re
import threading

import pytest
from aiohttp.test_utils import TestClient, TestServer

from arbiter_backend import supervise
from arbiter_backend.api import make_app
from arbiter_backend.supervise import Fault, InjectedFault, Supervisor, WorkerRecord, parse_faults
from arbiter_backend.topicwatch import TopicWatch, follow
from arbiter_backend.tracker import LatencyTracker

from ..support.waits import async_until, wait_for


def test_backoff_doubles_to_its_bound_and_a_stable_run_resets_it():
    w = WorkerRecord("x")
    delays = []
    for i in range(10):
        w.begin(float(i))
        delays.append(w.fail(RuntimeError("boom"), float(i) + 0.1, 1000.0 + i))
    assert delays[:3] == [0.2, 0.4, 0.8]
    assert max(d for d in delays if d is not None) == supervise.MAX_BACKOFF_S
    assert w.state == "restarting" and w.restarts == 10 and w.error == "RuntimeError: boom"
    w.begin(100.0)
    assert w.fail(ValueError("again"), 100.0 + supervise.STABLE_S, 2000.0) == supervise.MIN_BACKOFF_S
    assert w.to_json() == {
        "name": "x",
        "state": "restarting",
        "restarts": 11,
        "last_error": {"type": "ValueError", "message": "again"},
        "since": 2000.0,
    }


def test_a_worker_that_keeps_failing_at_once_is_given_up():
    w = WorkerRecord("x")
    for i in range(supervise.GIVE_UP_AFTER - 1):
        w.begin(float(i))
        assert w.fail(RuntimeError("boom"), float(i), 0.0) is not None
    assert w.fail(RuntimeError("boom"), 0.0, 0.0) is None
    assert w.state == "failed"
    w.stop(1.0)
    assert w.state == "failed"  # a failed worker stays failed when the backend stops


def test_a_worker_on_the_command_path_is_never_given_up():
    w = WorkerRecord("rclpy-executor", give_up=False)
    delays = []
    for i in range(supervise.GIVE_UP_AFTER * 3):
        w.begin(float(i))
        delays.append(w.fail(RuntimeError("boom"), float(i), 0.0))
    assert w.state == "restarting" and delays[-1] == supervise.MAX_BACKOFF_S


class Fatal(BaseException):
    """Not an Exception, as SystemExit and KeyboardInterrupt are not (those would end pytest itself)."""


@pytest.mark.filterwarnings("ignore::pytest.PytestUnhandledThreadExceptionWarning")  # re-raised: loud
def test_a_body_ended_by_a_base_exception_leaves_its_worker_failed_not_running():
    sup = Supervisor(faults={})
    stop = threading.Event()

    def body() -> None:
        sup.beat("x")
        raise Fatal("asked to exit")

    sup.thread("x", body, stop).join(5)
    w = sup.workers()[0]
    assert (w["state"], w["last_error"]) == ("failed", {"type": "Fatal", "message": "asked to exit"})


def test_an_injected_fault_comes_after_its_delay_from_the_first_start_as_many_runs_as_asked():
    w = WorkerRecord("x", fault=Fault(2.0, 2))
    w.begin(10.0)
    assert w.beat(11.0, 0.0) is True and w.state == "running"
    with pytest.raises(InjectedFault, match="ARBITER_FAULT=x") as first:
        w.beat(12.0, 0.0)
    w.fail(first.value, 12.0, 0.0)
    w.begin(12.5)
    with pytest.raises(InjectedFault) as second:  # the next run, at its first beat
        w.beat(12.5, 0.0)
    w.fail(second.value, 12.5, 0.0)
    w.begin(13.0)
    assert w.beat(20.0, 0.0) is True  # twice, then no more
    assert w.beat(30.0, 0.0) is False


@pytest.mark.parametrize(
    ("text", "faults"),
    [
        (None, {}),
        ("", {}),
        ("a", {"a": Fault()}),
        (" a@2 , b@0.5 ,", {"a": Fault(2.0), "b": Fault(0.5)}),
        ("a@1*4,b*2", {"a": Fault(1.0, 4), "b": Fault(0.0, 2)}),
    ],
)
def test_faults_parse(text, faults):
    assert parse_faults(text) == faults


@pytest.mark.parametrize(
    "text", ["a@", "@2", "a@-1", "a@soon", "a@inf", "a@nan", "a*0", "a*x", "a@1*", "a*99"]
)
def test_a_bad_fault_names_the_item(text):
    with pytest.raises(ValueError, match=re.escape(f"bad item {text!r}")):
        parse_faults(text)


def test_a_thread_that_fails_is_restarted_and_its_topics_are_unknown_until_it_runs_again():
    sup = Supervisor(faults={})
    watch = TopicWatch()
    watch.watch("/odom", "nav_msgs/msg/Odometry")
    follow(sup, "mon", watch, "monitor")
    stop, failed, go_on = threading.Event(), threading.Event(), threading.Event()
    runs = []

    def body() -> None:
        runs.append(1)
        if len(runs) == 1:
            sup.beat("mon")
            failed.set()
            raise OSError("the graph went away")
        go_on.wait(10)  # the second run: not a round done yet
        while not stop.is_set():
            sup.beat("mon")
            stop.wait(0.01)

    thread = sup.thread("mon", body, stop)
    assert failed.wait(5)
    assert wait_for(lambda: len(runs) == 2, 5)
    answer = watch.answer()
    assert answer["interrupted"] == "monitor restarted: OSError: the graph went away"
    assert [(t["state"], t["note"]) for t in answer["topics"]] == [("unknown", answer["interrupted"])]
    assert sup.workers()[0]["state"] == "restarting"
    go_on.set()
    assert wait_for(lambda: watch.answer()["interrupted"] is None, 5)
    assert watch.answer()["topics"][0]["state"] == "waiting"
    assert sup.workers()[0] | {"since": 0} == {
        "name": "mon",
        "state": "running",
        "restarts": 1,
        "last_error": {"type": "OSError", "message": "the graph went away"},
        "since": 0,
    }
    stop.set()
    thread.join(5)
    assert sup.workers()[0]["state"] == "stopped"


def test_a_name_runs_once():
    sup = Supervisor(faults={})
    stop = threading.Event()
    stop.set()
    sup.thread("x", lambda: None, stop).join(5)
    with pytest.raises(ValueError, match="x runs already"):
        sup.thread("x", lambda: None, stop)


async def test_a_task_is_restarted_after_an_injected_fault_and_stopped_when_cancelled():
    sup = Supervisor(faults={"loop": Fault()})
    rounds = []

    async def body() -> None:
        while True:
            sup.beat("loop")
            rounds.append(1)
            await asyncio.sleep(0.01)

    task = sup.task("loop", body)
    assert await async_until(lambda: len(rounds) >= 3, 5)
    w = sup.workers()[0]
    assert (w["state"], w["restarts"], w["last_error"]["type"]) == ("running", 1, "InjectedFault")
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert sup.workers()[0]["state"] == "stopped"


async def test_a_task_ended_by_a_base_exception_is_failed_and_health_says_degraded():
    sup = Supervisor(faults={})

    async def body() -> None:
        sup.beat("loop")
        raise Fatal("asked to exit")

    with pytest.raises(Fatal):
        await sup.task("loop", body)
    assert sup.workers()[0]["state"] == "failed"
    app = make_app(LatencyTracker(), workers=sup.workers)
    async with TestClient(TestServer(app)) as client:
        health = await (await client.get("/api/health")).json()
    assert (health["status"], health["failed_workers"]) == ("degraded", ["loop"])
