"""TickCollector: the oldest generation collected after control ticks, once a period, and the
collector's thresholds given back when the last session ends."""

from __future__ import annotations

import gc

import pytest

from arbiter_tui.session.collector import NEVER, TickCollector


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


@pytest.fixture
def thresholds():
    saved = gc.get_threshold()
    yield saved
    gc.set_threshold(*saved)


def test_collects_once_a_period_after_ticks(thresholds: tuple[int, int, int]) -> None:
    clock, calls = Clock(), []
    collector = TickCollector(1.0, clock, collect=lambda: calls.append(clock.t))
    collector.begin()
    try:
        done = []
        for _ in range(20):  # 2.5 s of ticks at 8 Hz (steps exact in binary)
            clock.t += 0.125
            done.append(collector.after_tick())
        assert sum(done) == 2 == len(calls) == collector.collections
        assert calls[1] - calls[0] == pytest.approx(1.0)
    finally:
        collector.end()


def test_automatic_full_collections_are_off_between_begin_and_end(
    thresholds: tuple[int, int, int],
) -> None:
    a, b = TickCollector(collect=lambda: None), TickCollector(collect=lambda: None)
    a.begin()
    b.begin()
    assert gc.get_threshold()[:2] == thresholds[:2] and gc.get_threshold()[2] == NEVER
    a.end()
    assert gc.get_threshold()[2] == NEVER  # b still runs
    a.end()  # a second end is a no-op, not a second release
    assert gc.get_threshold()[2] == NEVER
    b.end()
    assert gc.get_threshold() == thresholds


def test_nothing_is_collected_outside_begin_and_end(thresholds: tuple[int, int, int]) -> None:
    clock, calls = Clock(), []
    collector = TickCollector(1.0, clock, collect=lambda: calls.append(1))
    clock.t += 5.0
    assert not collector.after_tick()
    collector.begin()
    collector.end()
    clock.t += 5.0
    assert not collector.after_tick() and not calls


def test_collected_survivors_are_frozen_and_still_freed_when_dropped(
    thresholds: tuple[int, int, int],
) -> None:
    """After a collection what survived leaves the next walks (the permanent generation); an object
    without cycles among them is still freed by reference counting when its last reference goes."""
    import weakref

    class Payload:
        pass

    clock = Clock()
    collector = TickCollector(1.0, clock)
    collector.begin()
    try:
        kept = Payload()
        alive = weakref.ref(kept)
        clock.t += 1.0
        frozen_before = gc.get_freeze_count()
        assert collector.after_tick()
        assert gc.get_freeze_count() > frozen_before
        del kept
        assert alive() is None
    finally:
        collector.end()
        gc.unfreeze()


def test_the_whole_heap_only_after_a_quiet_spell_and_at_most_once_a_whole_period(
    thresholds: tuple[int, int, int],
) -> None:
    clock, calls = Clock(), []
    collector = TickCollector(
        1.0,
        clock,
        collect=lambda: calls.append("young"),
        collect_all=lambda: calls.append("whole"),
        whole_period_s=30.0,
        quiet_s=5.0,
    )
    collector.begin()
    try:
        for _ in range(40):  # 40 s of driving: never the whole heap
            clock.t += 1.0
            collector.after_tick(driving=True)
        assert calls == ["young"] * 40
        calls.clear()
        for _ in range(40):  # then 40 s idle: the whole heap once 5 s were quiet, then not before 30 s more
            clock.t += 1.0
            collector.after_tick(driving=False)
        assert calls.count("whole") == 2 and calls[4] == "whole" and calls[34] == "whole"
        assert "whole" not in calls[:4]
        assert collector.whole_collections == 2
        calls.clear()
        for step in range(60):  # a key every 4 s: never quiet for 5 s, so never the whole heap
            clock.t += 1.0
            collector.after_tick(driving=step % 4 == 0)
        assert calls == ["young"] * 60
    finally:
        collector.end()


def test_a_cycle_frozen_while_alive_is_freed_by_the_whole_heap_collection(
    thresholds: tuple[int, int, int],
) -> None:
    """What freezing costs and how it is paid back: a cycle alive at a freeze is not freed by later
    collections of the young part, only by the whole-heap one."""
    import weakref

    from arbiter_tui.session.collector import collect_and_freeze, collect_everything

    class Node:
        pass

    try:
        a, b = Node(), Node()
        a.other, b.other = b, a  # a cycle: reference counting never frees it
        gone = weakref.ref(a)
        collect_and_freeze()  # alive now: frozen
        del a, b
        collect_and_freeze()
        assert gone() is not None  # kept: frozen objects are not walked
        collect_everything()
        assert gone() is None
    finally:
        gc.unfreeze()
