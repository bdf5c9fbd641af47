"""AnalyticsStats speed and memory at 1k / 100k / 1M points, against a plain-Python transcription of the seed.

    python bench/bench_stats.py            # 1k, 100k, 1M
    python bench/bench_stats.py --sizes 1000 100000 --repeat 51

Prints one line per size and, last, one JSON object with every figure.
Targets: 1k < 0.1 ms, 1M < 30 ms, <= 100 bytes/point, >= 50x the plain version at 100k.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import random
import statistics
import time
import tracemalloc

from arbiter_tui.analytics.store import AnalyticsStore, DataPoint


def seed_plain_stats(pts: list[DataPoint]) -> dict[str, float]:
    """The seed's reduce/sort code, transcribed line by line to plain Python."""
    n = len(pts)
    avg_lin = sum(abs(p.linearVel) for p in pts) / n
    avg_ang = sum(abs(p.angularVel) for p in pts) / n
    max_lin = max(abs(p.linearVel) for p in pts)
    avg_dist = sum(p.distanceError for p in pts) / n
    avg_head = sum(abs(p.headingError) for p in pts) / n
    variance = sum((p.distanceError - avg_dist) ** 2 for p in pts) / n
    std = math.sqrt(variance)
    sorted_errors = sorted(p.distanceError for p in pts)
    p95 = sorted_errors[math.floor(n * 0.95)] or 0
    total = 0.0
    for i in range(1, n):
        total += math.hypot(pts[i].x - pts[i - 1].x, pts[i].y - pts[i - 1].y)
    return {
        "sampleCount": n,
        "avgLinearVel": avg_lin,
        "avgAngularVel": avg_ang,
        "maxLinearVel": max_lin,
        "avgDistanceError": avg_dist,
        "avgHeadingError": avg_head,
        "stdDevError": std,
        "p95Error": p95,
        "totalPathLength": total,
    }


def make_points(n: int, seed: int = 1) -> list[DataPoint]:
    rng = random.Random(seed)
    algos = ("manual", "go_to_goal", "pure_pursuit")
    return [
        DataPoint(
            1.7e12 + i * 100.0,
            rng.uniform(-5, 5),
            rng.uniform(-5, 5),
            rng.uniform(-3, 3),
            rng.uniform(-1, 1),
            rng.uniform(-2, 2),
            rng.uniform(0, 3),
            rng.uniform(-3, 3),
            algos[i % 3],
            rng.uniform(0.1, 1.0),
        )
        for i in range(n)
    ]


def median_seconds(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def bench_size(n: int, repeat: int) -> dict[str, float]:
    pts = make_points(n)
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    store = AnalyticsStore(max_data_points=n)
    store.start_collection()
    for p in pts:
        store.record(p)
    held = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    ours = median_seconds(store.stats, repeat)
    plain = median_seconds(lambda: seed_plain_stats(pts), max(3, repeat // 10) if n <= 100_000 else 3)
    got, want = store.stats().as_dict(), seed_plain_stats(pts)
    agree = all(math.isclose(got[k], want[k], rel_tol=1e-9, abs_tol=1e-9) for k in got)
    return {
        "n": n,
        "stats_ms": ours * 1e3,
        "plain_ms": plain * 1e3,
        "speedup": plain / ours,
        "bytes_per_point": held / n,
        "buffer_bytes_per_point": store.nbytes() / n,
        "agrees_with_plain": agree,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[1_000, 100_000, 1_000_000])
    ap.add_argument("--repeat", type=int, default=31, help="timed runs per size (median reported)")
    args = ap.parse_args()
    rows = []
    for n in args.sizes:
        row = bench_size(n, args.repeat)
        rows.append(row)
        print(
            f"n={n:>9,}  stats {row['stats_ms']:8.3f} ms  plain {row['plain_ms']:9.2f} ms  "
            f"x{row['speedup']:7.1f}  {row['bytes_per_point']:6.1f} B/point  agree={row['agrees_with_plain']}"
        )
    print(json.dumps({"bench": "stats", "python": platform.python_version(), "results": rows}))


if __name__ == "__main__":
    main()
