"""FrameClock: frames just after control ticks, spread out while commands leave late, closer again
once they are punctual (the UI gives way to the robot)."""

from __future__ import annotations

from arbiter_tui.session.frames import FrameClock

TICK = 0.1


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def run(clock: Clock, frames: FrameClock, ticks: int, late_s: float = 0.0) -> int:
    """``ticks`` control ticks, each frame drawn at once; how many frames were asked for."""
    asked = 0
    for _ in range(ticks):
        clock.t += TICK
        if frames.ticked(late_s):
            asked += 1
            frames.drawn()
    return asked


def test_punctual_ticks_give_the_asked_frame_rate() -> None:
    clock = Clock()
    frames = FrameClock(0.2, TICK, clock)
    assert run(clock, frames, 100) == 50  # 5 frames a second at 10 ticks a second
    assert frames.frame_s == 0.2 and frames.backed_off == 0


def test_no_frame_is_asked_for_while_one_is_pending() -> None:
    clock = Clock()
    frames = FrameClock(0.2, TICK, clock)
    clock.t += TICK
    assert frames.ticked()
    for _ in range(10):
        clock.t += TICK
        assert not frames.ticked()  # the UI has not drawn the last one
    frames.drawn()
    clock.t += TICK
    assert frames.ticked()


def test_late_commands_spread_frames_out_to_the_slowest() -> None:
    clock = Clock()
    frames = FrameClock(0.2, TICK, clock)
    run(clock, frames, 1, late_s=0.03)
    assert frames.frame_s == 0.2 * FrameClock.BACK_OFF
    run(clock, frames, 30, late_s=0.03)
    assert frames.frame_s == FrameClock.SLOWEST_S
    assert run(clock, frames, 100, late_s=0.03) == 10  # a frame a second, however late


def test_lateness_under_the_threshold_changes_nothing() -> None:
    clock = Clock()
    frames = FrameClock(0.2, TICK, clock)
    run(clock, frames, 50, late_s=FrameClock.LATE_S * 0.9)
    assert frames.frame_s == 0.2 and frames.backed_off == 0


def test_punctual_ticks_bring_frames_back_to_the_asked_rate_and_no_further() -> None:
    clock = Clock()
    frames = FrameClock(0.2, TICK, clock)
    run(clock, frames, 10, late_s=0.05)
    slow = frames.frame_s
    run(clock, frames, FrameClock.RECOVER_TICKS - 1)
    assert frames.frame_s == slow  # not yet: recovery waits for a run of punctual ticks
    run(clock, frames, 1)
    assert frames.frame_s == slow * FrameClock.RECOVER
    run(clock, frames, 2000)
    assert frames.frame_s == 0.2


def test_one_late_tick_restarts_the_punctual_run() -> None:
    clock = Clock()
    frames = FrameClock(0.2, TICK, clock)
    run(clock, frames, 1, late_s=0.05)
    slow = frames.frame_s
    run(clock, frames, FrameClock.RECOVER_TICKS - 1)
    run(clock, frames, 1, late_s=0.05)
    run(clock, frames, FrameClock.RECOVER_TICKS - 1)
    assert frames.frame_s == min(FrameClock.SLOWEST_S, slow * FrameClock.BACK_OFF)
