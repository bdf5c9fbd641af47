"""The analytics screen's sweep runs ``arbiter-tui compare`` in a real child process, at lower priority."""

import asyncio
import json
import os

import pytest

from arbiter_tui.analytics.linkcurve import SWEEP_LATENCIES_MS, CurveError
from arbiter_tui.session import link_sweep
from arbiter_tui.session.compare import AUTONOMOUS


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
