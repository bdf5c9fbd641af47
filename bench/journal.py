#!/usr/bin/env python
"""What the session's journal costs: CPU per second of session, and bytes per minute, in process.

A store fed as a driving console feeds it (``--rate`` samples a second, all in one run, a latency record
and a link sample per command at the same rate), and the journal's chunk step run every 0.5 s of
simulated session as its thread runs it (encode, zstd, write, fsync), timed with the process's CPU clock
(``time.process_time``: the journal's own work, not the wall time an fsync waits). ``--seconds`` of
session; the run's reference path is a square, so a running run's summary carries tracking figures.

    python bench/journal.py --seconds 600 --rate 10
"""

from __future__ import annotations

import argparse
import math
import random
import sys
import tempfile
import time
from pathlib import Path

from _common import emit

from arbiter_core.controllers import MISSIONS
from arbiter_tui.analytics.store import AnalyticsStore, DataPoint
from arbiter_tui.analytics.tracking import reference_path
from arbiter_tui.latency.clocksync import Sample
from arbiter_tui.session.journal import FLUSH_S, Journal, Sources


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=600.0, help="seconds of session")
    p.add_argument("--rate", type=float, default=10.0, help="samples (and commands) a second")
    a = p.parse_args()
    rng = random.Random(1)
    store = AnalyticsStore(1_000_000)
    store.start_collection()
    samples: list[Sample] = []
    journal = Journal(Sources(store, lambda: list(samples[-2000:])), Path(tempfile.mkdtemp()), 10**12,
                      flush_s=3600.0)  # fmt: skip
    journal.start()
    while journal._channels is None:  # opened on its thread; the steps are run here, timed
        time.sleep(0.01)
    t0 = 1.8e12
    run = store.begin_run("pure_pursuit", "square", t0, reference_path((0.0, 0.0), MISSIONS["square"]))
    n, per_step = 0, a.rate * FLUSH_S
    cpu, steps, worst = 0.0, 0, 0.0
    mono = time.monotonic()
    while n < a.seconds * a.rate:
        for _ in range(max(1, round(per_step))):
            t = t0 + 1000.0 * n / a.rate
            x, y = math.cos(n / 50), math.sin(n / 50)
            w, e_d, e_th = 0.2 + 0.01 * rng.random(), 0.05 * rng.random(), 0.02 * rng.random()
            lat = 10 + rng.random()
            store.record(DataPoint(t, x, y, n / 50, 0.5, w, e_d, e_th, "pure_pursuit", lat, run))
            samples.append(Sample(n, 10 + rng.random(), 20 + rng.random(), 10 + rng.random(), 19.0, mono + n))
            n += 1
        journal.latency(tuple(t / 1000 - k / a.rate for k in range(5, 0, -1)), tuple(10.0 for _ in range(5)))
        c = time.process_time()
        with journal._lock:
            journal._step()
            journal._sync()
        step = time.process_time() - c
        cpu, steps, worst = cpu + step, steps + 1, max(worst, step)
    path = journal.path
    size = path.stat().st_size if path else 0
    journal.close()
    emit({
        "bench": "journal", "seconds": a.seconds, "rate_hz": a.rate, "samples": n, "steps": steps,
        "cpu_ms_per_s": round(1000 * cpu / a.seconds, 3),
        "cpu_percent_of_core": round(100 * cpu / a.seconds, 3),
        "worst_step_ms": round(1000 * worst, 2), "mb_per_hour": round(size / a.seconds * 3600 / 1e6, 2),
    })  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
