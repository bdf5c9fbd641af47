"""Autonomous controllers never exceed the max speed and turn shown on the control screen.

The whole loop runs in simulated time: the console's ControlLoop (10 Hz) drives the client-side
simulator (50 Hz) through a SimLink; every command that reaches the link is checked.
"""

import pytest

from arbiter_core.controllers import MISSIONS
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.control.loop import ControlLoop
from arbiter_tui.control.teleop import Teleop
from arbiter_tui.link.sim import SimLink


class Clock:
    t = 0.0

    def __call__(self) -> float:
        return self.t


class CheckedSimLink(SimLink):
    def __init__(self, clock):
        super().__init__(clock=clock)
        self.sent: list[tuple[float, float]] = []

    def send(self, v, w):
        self.sent.append((v, w))
        return super().send(v, w)


def drive(algorithm: str, mission: str, speed: float, turn: float, limit_s: float = 900.0):
    clock = Clock()
    link = CheckedSimLink(clock)
    loop = ControlLoop(link, AnalyticsStore(), Teleop(speed=speed, turn=turn))
    loop.set_algorithm(algorithm)
    loop.set_mission(mission)
    assert loop.start_autonomous()
    steps = 0
    while loop.running and clock.t < limit_s:
        clock.t = round(clock.t + 0.02, 6)
        link.step()
        steps += 1
        if steps % 5 == 0:  # 10 Hz
            loop.tick_control(clock.t)
    return loop, link


@pytest.mark.parametrize("algorithm", ["go_to_goal", "pure_pursuit"])
@pytest.mark.parametrize("mission", list(MISSIONS))
def test_controllers_respect_a_low_cap_and_still_finish(algorithm, mission):
    loop, link = drive(algorithm, mission, speed=0.1, turn=0.3)
    assert loop.mission.done, f"{algorithm} did not finish {mission} at 0.1 m/s"
    assert len(link.sent) > 50
    assert max(abs(v) for v, _ in link.sent) <= 0.1 + 1e-12
    assert max(abs(w) for _, w in link.sent) <= 0.3 + 1e-12
    assert max(abs(v) for v, _ in link.sent) > 0.09  # it did drive at the cap, not below it


def test_the_cap_follows_the_speed_keys_during_a_run():
    clock = Clock()
    link = CheckedSimLink(clock)
    teleop = Teleop(speed=0.5, turn=1.0)
    loop = ControlLoop(link, AnalyticsStore(), teleop)
    loop.set_algorithm("go_to_goal")
    assert loop.start_autonomous()
    for _ in range(5):
        teleop.press("z", clock.t)  # x0.9 five times: 0.295 m/s
    for i in range(1, 30):
        clock.t = i * 0.1
        link.step()
        loop.tick_control(clock.t)
    assert teleop.speed == pytest.approx(0.5 * 0.9**5)
    assert max(abs(v) for v, _ in link.sent) <= teleop.speed + 1e-12
