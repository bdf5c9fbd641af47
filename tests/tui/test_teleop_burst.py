"""A stall's burst through the console's own key path (issue 55): keys parsed from one read on the
terminal's input thread (``burst``), answered by the session there, on the wire at once. The burst of a
key let go during the stall commands nothing past its first key's instant; a stop in it wins."""

from ..support.tui import burst, still_app


async def stalled(app, pilot) -> float:
    """``i`` held, then the link stalls: the deadman stops the robot; the clock is at the stall's end."""
    session, clock = app.session, app.fake_clock
    burst(app, "i")
    speed = session.teleop.speed
    assert session.link.sent[-1] == (speed, 0.0)
    clock.t += 0.3
    burst(app, "i")  # its first repeat
    clock.t += 3.0  # nothing arrives: the stall
    session.tick_control()
    assert session.link.sent[-1] == (0.0, 0.0) and not session.teleop.moving
    return speed


async def test_a_burst_after_a_stall_is_dropped_at_once():
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        await stalled(app, pilot)
        sent = len(app.session.link.sent)
        burst(app, *["i"] * 30)  # a second of repeats, delivered at once
        # the first key looked like a press; the second, with it, made it a replay: one zero, at once
        assert app.session.link.sent[sent:] == [(app.session.teleop.speed, 0.0), (0.0, 0.0)]
        assert not app.session.teleop.moving and app.session.teleop.bursts == 1
        app.fake_clock.t += 0.1
        app.session.tick_control()
        assert app.session.link.sent[-1] == (0.0, 0.0) and not app.session.teleop.moving


async def test_a_stop_in_a_burst_wins_over_the_keys_around_it():
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        await stalled(app, pilot)
        burst(app, *["i"] * 20, "space", *["i"] * 5)
        assert app.session.link.sent[-1] == (0.0, 0.0) and not app.session.teleop.moving
        for _ in range(8):  # the next ticks: nothing drives
            app.fake_clock.t += 0.1
            app.session.tick_control()
            assert not app.session.teleop.moving
        assert app.session.link.sent[-1] == (0.0, 0.0)


async def test_a_burst_whose_first_key_came_in_a_read_of_its_own_is_dropped_too():
    """The burst split across reads: its first key alone, the rest 12 ms later, then 60 ms (before, a
    second key over 10 ms after the first made the replay a steady hold that drove on)."""
    app = still_app()
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        for later in (0.012, 0.06):
            await stalled(app, pilot)
            burst(app, "i")
            app.fake_clock.t += later
            burst(app, *["i"] * 10)
            app.fake_clock.t += 0.012
            burst(app, *["i"] * 20)
            assert app.session.link.sent[-1] == (0.0, 0.0) and not app.session.teleop.moving
            app.fake_clock.t += 0.1
            app.session.tick_control()
            assert not app.session.teleop.moving
            app.fake_clock.t += 1.0  # the person presses again later
