"""The heartbeat's verdicts and the operator watch's transitions (session/heartbeat.py), in fake time."""

from arbiter_tui.session.heartbeat import (
    HEARD,
    PROBE_S,
    PROBING,
    SILENT,
    TMUX,
    UNHEARD,
    Heartbeat,
    OperatorBack,
    OperatorLost,
    OperatorUnknown,
    OperatorWatch,
    multiplexer,
    tmux_attached,
)


def test_the_verdicts_follow_the_answers():
    hb = Heartbeat(1.0)
    assert hb.verdict(0.0) == PROBING  # nothing asked yet
    hb.asked(10.0)
    assert hb.verdict(10.0 + PROBE_S - 0.01) == PROBING
    assert hb.verdict(10.0 + PROBE_S) == SILENT  # never answered
    hb.heard(13.5)  # a late first answer arms it still
    assert hb.round_trip_s() == 3.5
    assert hb.verdict(14.5) == HEARD
    assert hb.verdict(14.51) == UNHEARD
    assert abs(hb.silent_for(15.0) - 1.5) < 1e-9


def test_a_mission_holds_once_and_the_return_says_what_held():
    said: list[object] = []
    watch = OperatorWatch(1.0, said.append)
    hb = Heartbeat(1.0)
    watch.arm(hb)
    hb.asked(0.0)
    watch.heard(0.1)
    assert not watch.hold(0.5, "square")
    assert not watch.hold(1.2, None)  # unheard, but nothing drives on its own: nothing to hold
    assert watch.hold(1.3, "square")  # a mission started while unheard holds at once
    assert said == [OperatorLost("square", 1.2)]
    assert not watch.hold(1.4, None)  # (held: the mission stopped)
    watch.heard(3.0)
    assert not watch.hold(3.0, None)
    assert said[-1] == OperatorBack("square", 2.9)
    assert "square held" in said[-1].text() and "Press g" in said[-1].text()
    watch.heard(5.0)
    watch.hold(6.5, None)
    watch.heard(7.0)
    watch.hold(7.0, None)
    assert said[-1] == OperatorBack(None, 2.0) and "nothing drove" in said[-1].text()


def test_a_terminal_that_never_answers_is_said_once_and_never_holds():
    said: list[object] = []
    watch = OperatorWatch(1.0, said.append)
    hb = Heartbeat(1.0)
    watch.arm(hb)
    hb.asked(0.0)
    for t in (1.0, PROBE_S, PROBE_S + 1, PROBE_S + 60):
        assert not watch.hold(t, "square")
    assert len(said) == 1 and isinstance(said[0], OperatorUnknown) and "did not answer" in said[0].text


def test_off_and_tmux():
    said: list[object] = []
    off = OperatorWatch(0.0, said.append)
    off.arm(Heartbeat(0.0), "under screen ...")
    assert off.heartbeat is None and not off.hold(100.0, "square") and said == []
    watch = OperatorWatch(1.0, said.append)
    hb = Heartbeat(2.0, TMUX)
    watch.arm(hb)
    hb.asked(0.0)
    assert not watch.hold(PROBE_S + 1, "square") and said == []  # a session nobody attached: logged only
    assert multiplexer({"TMUX": "/tmp/tmux-0/default,1,0"}) == TMUX
    assert multiplexer({"STY": "123.pts-0.pi"}) == "screen" and multiplexer({}) is None
    assert tmux_attached("1\n") is True and tmux_attached("0\n") is False and tmux_attached("") is None


def test_frames_spread_while_the_answers_come_late_and_come_back_with_punctual_ticks():
    from arbiter_tui.session.frames import FrameClock

    t = [0.0]
    clock = FrameClock(0.2, 0.1, clock=lambda: t[0])
    clock.echoed(0.1)  # a screen the link keeps up with: nothing changes
    assert clock.frame_s == 0.2 and clock.stretch == 1.0
    clock.echoed(0.5)
    assert abs(clock.frame_s - 0.3) < 1e-9 and clock.backed_off == 1
    t[0] = 0.5
    clock.echoed(0.8)  # (within a second of the last back-off: the answers lag the frames)
    assert abs(clock.frame_s - 0.3) < 1e-9
    for step in range(1, 8):
        t[0] = step * 1.0
        clock.echoed(2.0)
    assert clock.frame_s == FrameClock.SLOWEST_S and clock.stretch == 5.0
    t[0] = 8.0
    clock.echoed(0.2)  # (between the bounds: as they are)
    assert clock.frame_s == FrameClock.SLOWEST_S
    for step in range(8, 13):  # answers on time again: closer, once a second
        t[0] = step + 0.5
        clock.echoed(0.05)
    assert abs(clock.frame_s - 0.2) < 0.01 and clock.frame_s >= 0.2
