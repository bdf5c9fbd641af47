"""The session thread's schedule (``session.robot.next_due``): how a control tick that overran, or
started late, moves the next one. Simulated time: each job starts when it is due or when the one before
it ended, whichever is later, as on the session's thread."""

from __future__ import annotations

import itertools

import pytest

from arbiter_tui.session.schedule import next_due

PERIOD = 0.1


def starts(durations: list[float], stall_before: dict[int, float] | None = None) -> list[float]:
    """When each tick started, given how long each took (the tick and the collection after it)."""
    stall_before = stall_before or {}
    due, free, out = PERIOD, 0.0, []
    for i, took in enumerate(durations):
        started = max(due, free) + stall_before.get(i, 0.0)
        out.append(started)
        free = started + took
        due = next_due(due, started, PERIOD)
    return out


def gaps(times: list[float]) -> list[float]:
    return [round(b - a, 6) for a, b in itertools.pairwise(times)]


def test_an_overrun_delays_the_next_tick_by_the_overrun_not_by_a_whole_period():
    # the third tick's collection runs 80 ms past the next due time (the walk over a second's new objects,
    # under a Pi-class quota): the fourth tick goes as soon as it is over, the next a period after it
    durations = [0.001, 0.001, 0.18, 0.001, 0.001, 0.001]
    assert gaps(starts(durations)) == pytest.approx([0.1, 0.1, 0.18, 0.1, 0.1])


def test_a_stall_longer_than_a_period_sends_no_burst():
    # the process stopped for 350 ms before the third tick: the ticks after it are a period apart
    got = gaps(starts([0.001] * 6, stall_before={2: 0.35}))
    assert got[1] == pytest.approx(0.45)
    assert got[2:] == pytest.approx([0.1, 0.1, 0.1])


def test_on_time_ticks_keep_their_grid_however_late_each_wakes_within_it():
    # each tick wakes 3 ms late: the rate stays the period's, it does not drift by 3 ms a tick
    due, out = PERIOD, []
    for _ in range(50):
        started = due + 0.003
        out.append(started)
        due = next_due(due, started, PERIOD)
    assert out[-1] - out[0] == pytest.approx(49 * PERIOD)


def test_the_rule():
    assert next_due(1.0, 1.0, 0.1) == pytest.approx(1.1)  # on time
    assert next_due(1.0, 1.04, 0.1) == pytest.approx(1.1)  # a little late: back on the grid
    assert next_due(1.0, 1.09, 0.1) == pytest.approx(1.19)  # over half a period late: a period from its start
    assert next_due(1.0, 1.25, 0.1) == pytest.approx(1.35)


def run_schedule(steps: bool, ticks: int = 20) -> tuple[int, float]:
    """A real Schedule (its own thread) until ``ticks`` control ticks ran: how often it asked the link to
    step, and how long that took."""
    import threading
    import time

    from arbiter_tui.latency.clocksync import LatencyMeter
    from arbiter_tui.session.schedule import Jobs, Schedule

    asked, done = [0], threading.Event()
    count = [0]

    def tick() -> bool:
        count[0] += 1
        if count[0] >= ticks:
            done.set()
        return False

    def step() -> bool:
        asked[0] += 1
        return steps

    meter = LatencyMeter()
    jobs = Jobs(tick=tick, sample=lambda: None, step=step, meter=lambda: meter, driving=lambda: False,
                control_s=0.01, sample_s=0.1, step_s=0.002)  # fmt: skip
    schedule = Schedule(jobs)
    t0 = time.monotonic()
    schedule.start()
    try:
        assert done.wait(30)
    finally:
        schedule.stop()
    return asked[0], time.monotonic() - t0


def test_a_link_with_nothing_to_step_is_asked_four_times_a_second_not_at_the_step_rate():
    """A rosbridge link runs on its own: the session's thread does not wake 50 times a second to step it."""
    from arbiter_tui.session.schedule import NO_STEP_RECHECK_S

    asked, took = run_schedule(steps=False)
    assert asked <= 2 + took / NO_STEP_RECHECK_S, (asked, took)
    stepped, took = run_schedule(steps=True)
    assert stepped >= 20, stepped  # a simulator is stepped at its rate (several steps per tick)
