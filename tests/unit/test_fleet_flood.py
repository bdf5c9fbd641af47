"""A robot over its kinds' rates (arbiter_tui.fleet.flood, the console's client): the excess dropped before
it is parsed, the row marked "flooding: N/s", a robot at its own rates never touched; keys that are not a
robot's payload dropped and counted where a person and a script see them."""

import time

import pytest

from arbiter_core import fleet
from arbiter_tui.fleet import client as client_mod
from arbiter_tui.fleet.client import ConsoleSettings, FleetClient
from arbiter_tui.fleet.flood import BURST, FLOOD_FACTOR, FLOOD_HOLD_S, Meter
from arbiter_tui.fleet.rows import BAD, FleetModel, cells

W = 1_800_000_000.0


def test_a_robot_at_its_kinds_rates_is_never_dropped_even_with_jitter():
    m = Meter()
    t = 0.0
    while t < 120.0:  # two minutes: a status a second (two at once now and then), the others on theirs
        kinds = [fleet.STATUS] * (2 if int(t) % 17 == 0 else 1)
        kinds += [fleet.LATENCY] * (int(t) % 2 == 0) + [fleet.TOPICS] * (int(t) % 5 == 0)
        assert all(m.admit(k, t) for k in kinds), t
        t += 1.0
    assert m.dropped == 0 and m.flooding(t) is None


def test_a_flood_is_dropped_beyond_its_rate_and_named_while_it_lasts():
    m = Meter()
    passed = sum(m.admit(fleet.STATUS, i / 1000) for i in range(3000))  # 1000 a second for 3 s
    assert passed <= BURST + FLOOD_FACTOR * 3 + 1
    assert m.flooding(3.0) == pytest.approx(1000, rel=0.05)
    assert m.flooding(3.0 + FLOOD_HOLD_S + 0.1) is None  # quiet again: no longer marked


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def status(name, t):
    return fleet.encode(fleet.Status(name, W + t, W - 60, "nobody", "embedded, sim"))


def test_the_console_parses_no_more_than_the_rate_names_the_flood_and_counts_what_it_drops(monkeypatch):
    noisy = [status("noisy", i / 1000) for i in range(2000)]  # encoded before decode is counted
    calm = [status("calm", t) for t in (0.0, 1.0)]
    decoded = []
    real = fleet.decode

    def counting(data, kind, robot):
        decoded.append(robot)
        return real(data, kind, robot)

    monkeypatch.setattr(client_mod.fleet, "decode", counting)
    mono = Clock()
    c = FleetClient(ConsoleSettings(connect=("tcp/127.0.0.1:7447",)), FleetModel(), lambda: W + mono.t, mono)
    try:
        for name in ("noisy", "calm"):
            c.model.token(name, True, W, 0.0)
        for i, data in enumerate(noisy):  # 1000 valid statuses a second from one robot for 2 s
            mono.t = i / 1000
            c.take(fleet.key("noisy", fleet.STATUS), data)
            if i % 1000 == 0:  # one a second from another
                c.take(fleet.key("calm", fleet.STATUS), calm[i // 1000])
        for odd in ("arbiter/../status", "arbiter/a name/status", "arbiter/" + "x" * 300 + "/status"):
            c.take(odd, b"{}")
        view = c.view()
        rows = {r.name: r for r in view.rows}
        assert decoded.count("noisy") <= BURST + FLOOD_FACTOR * 2 + 1 and decoded.count("calm") == 2
        assert rows["noisy"].severity == BAD and cells(rows["noisy"])[-1].startswith("flooding: 10")
        assert cells(rows["noisy"])[-1].endswith("/s, the excess dropped")
        assert rows["calm"].flooding is None and rows["calm"].severity < BAD
        assert view.to_json()["dropped"] == {"odd_keys": 3, "over_rate": 2000 - decoded.count("noisy")}
        assert view.names("flooding") == ("noisy",)
    finally:
        c.close()


def test_a_flood_costs_the_console_little_per_dropped_payload():
    """Dropped before parsing: a dropped status costs a few microseconds, not a JSON parse."""
    mono = Clock()
    c = FleetClient(ConsoleSettings(connect=("tcp/127.0.0.1:7447",)), FleetModel(), lambda: W + mono.t, mono)
    try:
        data = status("noisy", 0.0)
        c.take(fleet.key("noisy", fleet.STATUS), data)
        t0 = time.perf_counter()
        for i in range(5000):
            mono.t = i / 1e6  # 5000 in 5 ms: all but a burst dropped
            c.take(fleet.key("noisy", fleet.STATUS), data)
        per = (time.perf_counter() - t0) / 5000
        assert per < 100e-6, per  # a generous bound for a loaded CI box (about 3 us here)
        print(f"a dropped payload: {per * 1e6:.1f} us")
    finally:
        c.close()
