"""The analytics screen's sweep runs ``arbiter-tui compare`` in a real child process, at lower priority."""

import asyncio
import contextlib
import json
import os
import signal
import subprocess
import sys
from functools import partial

import pytest

from arbiter_tui.analytics.linkcurve import SWEEP_LATENCIES_MS, CurveError
from arbiter_tui.session import link_sweep
from arbiter_tui.session.compare import AUTONOMOUS

from ..support.tui import FakeClock
from ..support.waits import wait_for as poll_until


def test_the_child_process_answers_a_curve_per_controller():
    curve = asyncio.run(link_sweep.sweep_curve("corner", 0.5, 1.0))
    assert curve.mission == "corner" and curve.latencies_ms == SWEEP_LATENCIES_MS
    assert {name for name, _ys in curve.errors} == set(AUTONOMOUS)
    assert all(len(ys) == len(SWEEP_LATENCIES_MS) and min(ys) >= 0 for _name, ys in curve.errors)


def test_a_failing_child_says_why(monkeypatch):
    real = link_sweep.command
    monkeypatch.setattr(link_sweep, "command", lambda m, s, t: [*real(m, s, t), "--trials", "0"])
    with pytest.raises(CurveError, match="--trials"):
        asyncio.run(link_sweep.sweep_curve("square", 0.5, 1.0))


def test_cancelling_kills_the_child(monkeypatch):
    monkeypatch.setattr(link_sweep, "command", lambda m, s, t: ["sleep", "30"])
    started = []
    real_exec = asyncio.create_subprocess_exec

    async def cancel_it() -> None:
        running = asyncio.Event()

        async def exec_and_tell(*args, **kwargs):
            proc = await real_exec(*args, **kwargs)
            started.append(proc.pid)
            running.set()
            return proc

        monkeypatch.setattr(asyncio, "create_subprocess_exec", exec_and_tell)
        task = asyncio.create_task(link_sweep.sweep_curve("square", 0.5, 1.0))
        await asyncio.wait_for(running.wait(), 30)  # the child is running: cancel now
        task.cancel()
        with pytest.raises(asyncio.CancelledError):  # not a 10 s wait for the child's 30 s to end
            await asyncio.wait_for(task, 10)

    asyncio.run(cancel_it())
    (pid,) = started
    assert not os.path.exists(f"/proc/{pid}")  # killed and reaped (not even a zombie)


def test_a_setting_swept_once_is_read_from_the_cache_afterwards(monkeypatch):
    """The sweep runs once per setting: the next session reads its file, and the control loop's CPU
    quota pays nothing (a child under a cgroup quota spends the console's, nice or not)."""
    first = asyncio.run(link_sweep.sweep_curve("corner", 0.5, 1.0))
    path = link_sweep.cache_path("corner", 0.5, 1.0)
    assert path.is_file() and str(path).startswith(os.environ["XDG_CACHE_HOME"])

    async def no_child(*args, **kwargs):
        raise AssertionError("the child ran although the setting was cached")

    with monkeypatch.context() as patched:
        patched.setattr(asyncio, "create_subprocess_exec", no_child)
        assert asyncio.run(link_sweep.sweep_curve("corner", 0.5, 1.0)) == first
    assert link_sweep.cache_path("corner", 0.6, 1.0) != path  # another speed: another sweep
    path.write_text('{"runs": [trunc')  # damaged: computed again, and kept whole
    assert asyncio.run(link_sweep.sweep_curve("corner", 0.5, 1.0)) == first
    assert json.loads(path.read_text())["sweep"]


# -- a console with no core to spare: the sweep waits while the robot drives ----------------------------
BODY = {  # the smallest compare --json sweep answer: one controller at two latencies
    "sweep": [
        {"link": {"latency_ms": ms}, "missions": [
            {"mission": "square", "ranking": [{"algorithm": "pure_pursuit", "xte_mean_m": {"mean": e}}]}
        ]}
        for ms, e in ((0.0, 0.01), (100.0, 0.05))
    ]
}  # fmt: skip


def cpu_bound_child(cpu_s: float, body: dict) -> list[str]:
    """A child that computes for ``cpu_s`` of CPU time (not wall time: held, it gets no further), then
    answers ``body``."""
    script = (
        "import json, sys, time\n"
        f"while time.process_time() < {cpu_s}: pass\n"
        f"sys.stdout.write(json.dumps({body!r}))\n"
    )
    return [sys.executable, "-c", script]


def state(pid: int) -> str:
    """The process's state letter (T: stopped), '' once it is gone."""
    try:
        return open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0]
    except OSError:
        return ""


wait_for = partial(poll_until, timeout=10.0, interval=0.01)


def test_no_core_to_spare_holds_the_child_while_the_robot_drives():
    clock = FakeClock(0.0)
    pause = link_sweep.SweepPause(lambda: 0.25, clock)
    child = subprocess.Popen(cpu_bound_child(60, BODY), stdout=subprocess.DEVNULL)
    try:
        pause.child(child.pid)
        assert wait_for(lambda: state(child.pid) in ("R", "S")) and not pause.paused
        pause.driving(True)  # a control tick that drove
        assert pause.paused and wait_for(lambda: state(child.pid) == "T")
        pause.driving(False)
        clock.t += link_sweep.RESUME_S / 2  # still, but not long enough: a key pressed again soon
        pause.driving(False)
        assert pause.paused and wait_for(lambda: state(child.pid) == "T")
        clock.t += link_sweep.RESUME_S / 2
        pause.driving(False)
        assert not pause.paused and wait_for(lambda: state(child.pid) in ("R", "S"))
        pause.driving(True)
        assert pause.paused and wait_for(lambda: state(child.pid) == "T") and pause.holds == 2
        pause.child(None)  # the child ended (or was killed): nothing more is signalled
        pause.driving(False)
        clock.t += 2 * link_sweep.RESUME_S
        pause.driving(False)
        assert not pause.paused and state(child.pid) == "T"
    finally:
        child.kill()
        child.wait()


def test_a_core_to_spare_never_holds_the_child():
    pause = link_sweep.SweepPause(lambda: 4.0)  # a Raspberry Pi 4's four cores
    child = subprocess.Popen(["sleep", "30"])
    try:
        pause.child(child.pid)
        pause.driving(True)
        assert wait_for(lambda: state(child.pid) == "S") and not pause.paused and pause.holds == 0
    finally:
        child.kill()
        child.wait()


def test_a_held_sweep_ends_once_the_robot_stands_still_and_its_pause_is_not_a_timeout(monkeypatch):
    """The child's time limit counts its running time: held longer than the limit, the sweep still
    ends with its curve once the robot stops. A child started while the robot drives is held at once."""
    monkeypatch.setattr(link_sweep, "command", lambda m, s, t: cpu_bound_child(0.3, BODY))
    monkeypatch.setattr(link_sweep, "TIMEOUT_S", 2.5)  # the child's start and 0.3 s of CPU, on a loaded CI
    monkeypatch.setattr(link_sweep, "POLL_S", 0.05)
    clock = FakeClock(0.0)
    pause = link_sweep.SweepPause(lambda: 0.25, clock)
    pause.driving(True)
    pids: list[int] = []
    real_child = pause.child

    def child(pid):
        if pid is not None:
            pids.append(pid)
        real_child(pid)

    pause.child = child

    async def drive_then_stop():
        task = asyncio.create_task(link_sweep.sweep_curve("square", 0.5, 1.0, cache=False, pause=pause))
        while not pids:
            await asyncio.sleep(0.01)
        assert pause.paused and wait_for(lambda: state(pids[0]) == "T")  # held from its first instruction
        while pause.held_s() <= link_sweep.TIMEOUT_S + 0.5:  # held past the time limit
            await asyncio.sleep(0.05)
        assert not task.done() and state(pids[0]) == "T"
        pause.driving(False)
        clock.t += link_sweep.RESUME_S
        pause.driving(False)
        return await asyncio.wait_for(task, 30)

    curve = asyncio.run(drive_then_stop())
    assert curve.errors == (("pure_pursuit", (0.01, 0.05)),)
    assert not pause.paused and state(pids[0]) == ""


def test_a_running_child_that_outlives_its_limit_is_killed(monkeypatch):
    monkeypatch.setattr(link_sweep, "command", lambda m, s, t: cpu_bound_child(60, BODY))
    monkeypatch.setattr(link_sweep, "TIMEOUT_S", 0.5)
    monkeypatch.setattr(link_sweep, "POLL_S", 0.05)
    pause = link_sweep.SweepPause(lambda: 0.25)
    pids: list[int] = []
    real_child = pause.child
    pause.child = lambda pid: (pids.append(pid), real_child(pid))
    with pytest.raises(TimeoutError):
        asyncio.run(link_sweep.sweep_curve("square", 0.5, 1.0, cache=False, pause=pause))
    assert state(pids[0]) == ""


def test_the_child_dies_with_the_console():
    """A held child whose console dies (killed, or its watchdog's hard exit) does not wait forever."""
    script = (
        "import asyncio, os, sys\n"
        "from arbiter_tui.session import link_sweep\n"
        "link_sweep.command = lambda m, s, t: ['sleep', '60']\n"
        "pause = link_sweep.SweepPause(lambda: 0.25)\n"
        "pause.driving(True)\n"
        "real = pause.child\n"
        "def child(pid):\n"
        "    real(pid)\n"
        "    if pid is not None:\n"
        "        print(pid, flush=True)\n"
        "        os._exit(0)\n"
        "pause.child = child\n"
        "asyncio.run(link_sweep.sweep_curve('square', 0.5, 1.0, cache=False, pause=pause))\n"
    )
    console = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    pid = int(console.stdout.split()[0])
    try:
        assert wait_for(lambda: state(pid) in ("", "Z"))  # killed (a zombie until its new parent reaps it)
    finally:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
