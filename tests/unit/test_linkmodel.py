"""The modelled link of simulated runs: exact delays in simulated time, order, loss; the robot behind it."""

import math
import random

import pytest

from arbiter_core.linkmodel import DelayLine, LinkModel, LinkModelError
from arbiter_tui.link.modelled import ModelledLink
from arbiter_tui.session.compare import AUTONOMOUS, run_one


def test_a_command_sent_at_t_arrives_at_t_plus_latency_exactly():
    line: DelayLine[str] = DelayLine(0.1)
    assert line.send(1.0, "a") == pytest.approx(1.1)
    assert line.send(1.05, "b") == pytest.approx(1.15)
    assert line.due(1.0999) == []
    assert line.due(1.1) == [(pytest.approx(1.1), "a")]
    assert line.due(2.0) == [(pytest.approx(1.15), "b")]


def test_jitter_is_half_normal_and_never_reorders():
    dense: DelayLine[int] = DelayLine(0.05, jitter_s=0.02, rng=random.Random(7))
    arrivals = [dense.send(i * 0.01, i) for i in range(2000)]
    assert min(a - i * 0.01 for i, a in enumerate(arrivals)) >= 0.05 - 1e-12  # never before the latency
    assert arrivals == sorted(arrivals)  # in order: a command waits behind the one before it
    assert [item for _, item in dense.due(math.inf)] == list(range(2000))
    # sparse (nothing to wait behind): the extra delay is half-normal, mean sigma * sqrt(2 / pi)
    sparse: DelayLine[int] = DelayLine(0.05, jitter_s=0.02, rng=random.Random(7))
    extra = [sparse.send(float(i), i) - i - 0.05 for i in range(4000)]
    assert min(extra) >= 0.0
    assert sum(extra) / len(extra) == pytest.approx(0.02 * math.sqrt(2 / math.pi), rel=0.05)


def test_loss_drops_its_fraction_deterministically_for_a_seed():
    def dropped(seed: int) -> int:
        line: DelayLine[int] = DelayLine(0.0, loss=0.2, rng=random.Random(seed))
        for i in range(5000):
            line.send(float(i), i)
        return line.dropped

    assert dropped(1) == dropped(1)
    assert dropped(1) / 5000 == pytest.approx(0.2, abs=0.02)


@pytest.mark.parametrize(
    "kwargs", [{"latency_s": -0.1}, {"jitter_s": math.nan}, {"loss": 1.0}, {"odom_delay_s": math.inf}]
)
def test_impossible_links_are_refused(kwargs):
    with pytest.raises(LinkModelError):
        LinkModel(**kwargs)


class Clock:
    t = 0.0

    def __call__(self) -> float:
        return self.t


def test_the_robot_acts_on_a_command_only_once_it_arrives_and_the_console_sees_it_late():
    clock = Clock()
    link = ModelledLink(LinkModel(latency_s=0.3, odom_delay_s=0.2), clock)
    link.send(0.5, 0.0)
    for n in range(1, 36):  # 0.7 s at 50 Hz
        clock.t = n * 0.02
        link.step()
        if clock.t <= 0.3 + 1e-9:
            assert link.true_pose.x == 0.0, clock.t  # the command has not arrived
    moving = link.true_pose.x
    seen = link.telemetry.snapshot()[0].x
    assert moving > 0.1 and 0.0 < seen < moving  # the console sees where the robot was 0.2 s ago
    for n in range(36, 101):
        clock.t = n * 0.02
        link.step()
    # the robot's own deadman stopped it 0.5 s after the command arrived: at most 0.5 m/s x 0.5 s
    assert link.true_pose.x <= 0.25 + 1e-9
    assert link.telemetry.snapshot()[0].x == pytest.approx(link.true_pose.x)  # and the console caught up


def test_a_perfect_modelled_link_is_the_plain_simulator():
    for algorithm in AUTONOMOUS:
        plain = run_one(algorithm, "square")
        modelled = run_one(algorithm, "square", link_model=LinkModel())
        assert modelled.stats.avgDistanceError == pytest.approx(plain.stats.avgDistanceError)
        assert modelled.time_s == pytest.approx(plain.time_s)


def test_every_controller_tracks_worse_at_300_ms_than_at_0_over_10_seeds():
    for algorithm in AUTONOMOUS:
        for seed in range(10):
            at = {
                ms: run_one(algorithm, "square", link_model=LinkModel(ms / 1e3, jitter_s=0.01), seed=seed)
                for ms in (0, 300)
            }
            assert at[300].completed and at[0].completed
            assert at[300].stats.avgDistanceError > at[0].stats.avgDistanceError, (algorithm, seed)
