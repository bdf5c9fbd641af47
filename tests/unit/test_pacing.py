"""The pacer of a slow client's big frames (arbiter_backend/pacing.py), on synthetic write times."""

import pytest

from arbiter_backend import pacing as P

FRAG = 65_600  # a 64 KiB rosbridge fragment with its JSON wrapper
CAMERA = (30.0, 921_700)  # a 640x480 rgb8 image at 30 Hz, as JSON


class Camera:
    """Tells the pacer of the frames the client's big topic brings, up to a time."""

    def __init__(self, pacer, fps=CAMERA[0], size=CAMERA[1]):
        self.pacer, self.period, self.size, self.next = pacer, 1.0 / fps, size, 0.0

    def until(self, t):
        while self.next <= t:
            self.pacer.offered(self.size, self.next)
            self.next += self.period


def backlogged(pacer, rate_bps, seconds, start=0.0, every=4):
    """Writes as a client reading at ``rate_bps`` makes them return: the library waits for the drain
    every ``every`` writes, for as long as the client takes to read what was written since."""
    t = start
    n = 0
    camera = Camera(pacer)
    camera.next = start
    while t - start < seconds:
        camera.until(t)
        n += 1
        if n % every:
            pacer.wrote(FRAG, t, t + 0.0001)
            t += 0.0001
        else:
            wait = every * FRAG / rate_bps
            pacer.wrote(FRAG, t, t + wait)
            t += wait
    return t


def test_a_client_that_keeps_up_is_never_paced():
    pacer = P.Pacer()
    camera = Camera(pacer)
    t = 0.0
    for _ in range(1000):
        camera.until(t)
        pacer.wrote(FRAG, t, t + 0.0005)  # never waits for the socket
        t += 0.033
    assert pacer.rate is None and pacer.next_at() == 0.0


def test_the_read_rate_is_measured_while_backlogged_and_big_frames_wait_for_it():
    pacer = P.Pacer()
    t = backlogged(pacer, 6e6, 1.5)  # a second of the camera's offer is known too
    assert pacer.rate == pytest.approx(6e6, rel=0.05) and pacer.paced
    pacer.wrote(FRAG, t, t + 0.0001)
    assert pacer.next_at() == pytest.approx(t + FRAG / (P.SHARE * pacer.rate))
    # the small frames are not paced and do not count
    before = (pacer.rate, pacer.next_at())
    pacer.wrote(200, t + 0.001, t + 0.5)
    assert (pacer.rate, pacer.next_at()) == before


def test_a_pause_starts_a_new_measurement_and_a_faster_client_is_found_again():
    pacer = P.Pacer()
    t = backlogged(pacer, 2e6, 1.0)
    assert pacer.rate == pytest.approx(2e6, rel=0.05)
    # paced below its rate, no write waits: after PROBE_AFTER_S the estimate grows, step by step
    t += 0.05
    camera = Camera(pacer)
    camera.next = t
    for _ in range(int(P.PROBE_AFTER_S / 0.04) + 1):
        camera.until(t)
        pacer.wrote(FRAG, t, t + 0.0001)
        t += 0.04
    assert pacer.rate == pytest.approx(2e6 * P.PROBE, rel=0.05)
    # the client is now faster: the idle second between does not count, the new stretch measures it
    t = backlogged(pacer, 9e6, 1.0, start=t + 1.0)
    assert pacer.rate == pytest.approx(9e6, rel=0.05)


def simulate(
    frame_bytes,
    rate_bps,
    seconds,
    buffers=384 * 1024,
    limit=256 * 1024,
    paced=True,
    fps=30.0,
    starts_too=False,
):
    """A writer that always has a frame ready (a camera, queue_length 1) and honours the pacer, against
    a client reading ``rate_bps`` behind ``buffers`` bytes of socket buffers; like aiohttp, the writer
    waits for the drain (until only ``buffers`` are queued) once it has written ``limit`` bytes since
    it last did. Returns the pacer's rates after each write, the frames written a second and the mean
    bytes queued when a frame starts (what a small message would wait behind), over the last half
    (and with ``starts_too`` each frame's (start, bytes queued then))."""
    pacer = P.Pacer()
    camera = Camera(pacer, fps)
    t, queued, out, starts, rates = 0.0, 0.0, 0, [], []

    def drain(until):
        nonlocal t, queued
        queued = max(0.0, queued - (until - t) * rate_bps)
        t = until

    while t < seconds:
        camera.until(t)
        drain(max(t + 0.0001, pacer.next_at() if paced else 0.0))
        start = t
        starts.append((start, queued))
        queued += frame_bytes
        out += frame_bytes
        if out > limit:
            out = 0
            if queued > buffers:
                drain(t + (queued - buffers) / rate_bps)
        drain(t + 0.0001)
        pacer.wrote(frame_bytes, start, t)
        rates.append((start, pacer.rate, pacer.paced))
    half = seconds / 2
    backlog = [q for s, q in starts if s >= half]
    out = [(r, p) for s, r, p in rates if s >= half], len(backlog) / half, sum(backlog) / len(backlog)
    return (*out, [(s, q) for s, q in starts if s >= half]) if starts_too else out


def test_a_paced_client_gets_most_of_its_rate_in_fragments_and_its_buffers_stay_nearly_empty():
    rate = 6e6
    rates, frames_per_s, backlog = simulate(FRAG, rate, 60.0)
    assert all(paced for _r, paced in rates)
    rates = [r for r, _p in rates]
    _, unpaced, unpaced_backlog = simulate(FRAG, rate, 60.0, paced=False)
    print(
        f"rate {min(rates) / rate:.2f}-{max(rates) / rate:.2f} of the client's, "
        f"{frames_per_s:.2f} frames/s of {unpaced:.2f}, backlog {backlog:.0f} B of {unpaced_backlog:.0f}"
    )
    # measured, and not talked down by its own pauses: it gets most of the frames it could take
    assert min(rates) > 0.75 * rate
    assert frames_per_s > 0.7 * unpaced
    # what a small message waits behind, on average: a fraction of the unpaced backlog
    assert backlog < 0.5 * unpaced_backlog


def waited_over(starts, frame_bytes, rate_bps, wait_s):
    """The share of the time a small message sent then would wait longer than ``wait_s``: behind
    each frame, every byte queued when it started and the frame itself."""
    over = sum(max(0.0, (queued + frame_bytes) / rate_bps - wait_s) for _s, queued in starts)
    return over / (starts[-1][0] - starts[0][0])


@pytest.mark.parametrize("rate", [6e6, 2e6])
def test_a_frame_that_holds_the_wire_too_long_is_spaced_so_small_messages_wait_little(rate):
    """A 640x480 frame as JSON, unfragmented, to a client reading 6 (2) MB/s holds everything behind
    it 150 (460) ms: spaced so that a small message waits over WAIT_S at most OVER_WAIT_SHARE of the
    time, its estimate kept by the lone frames' own writes, never talked down to nothing."""
    frame = 921_700
    rates, frames_per_s, _backlog, starts = simulate(frame, rate, 120.0, starts_too=True)
    _, _, _, unpaced = simulate(frame, rate, 120.0, paced=False, starts_too=True)
    rates = [r for r, _p in rates]
    over = waited_over(starts, frame, rate, P.WAIT_S)
    print(
        f"rate {min(rates) / rate:.2f}-{max(rates) / rate:.2f} of the client's, {frames_per_s:.2f} "
        f"frames/s, over {P.WAIT_S * 1e3:.0f} ms {over:.3f} of the time "
        f"(unpaced {waited_over(unpaced, frame, rate, P.WAIT_S):.3f})"
    )
    assert 0.75 * rate < min(rates) and max(rates) < 1.3 * rate
    assert over <= 0.05  # the small topic's p95 stays within WAIT_S
    assert waited_over(unpaced, frame, rate, P.WAIT_S) > 0.5  # which it did not without pacing
    hold = frame / rate - P.WAIT_S
    assert frames_per_s > 0.5 * P.OVER_WAIT_SHARE / hold  # and frames still come, as many as that allows


def test_a_client_that_keeps_up_on_average_is_not_paced_for_lagging_a_moment():
    """Reading 40 MB/s of a 27.6 MB/s camera: its writes wait for the drain now and then, and its
    samples say it reads faster than the camera brings: never paced, every frame goes (before,
    a busy machine's momentary lag cut a 1280x720 stream from 30 to 22 frames/s)."""
    rates, _frames, _backlog = simulate(921_700, 40e6, 20.0, fps=30.0)
    assert not any(paced for _r, paced in rates)
    assert any(r is not None for r, _p in rates)  # it was measured
