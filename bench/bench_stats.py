"""AnalyticsStats speed and memory at 1k / 100k / 1M points, against a plain-Python transcription of the seed.

    python bench/bench_stats.py            # 1k, 100k, 1M; runs; the analytics screen at 10k and 1M
    python bench/bench_stats.py --sizes 1000 100000 --repeat 51 --screen-sizes 1000000

Prints one line per figure and, last, one JSON object with every figure.
Targets: 1k < 0.1 ms, 1M < 30 ms, <= 100 bytes/point, >= 50x the plain version at 100k; the nine
stats of 100 runs of 10,000 points each, from scratch, <= 50 ms; one analytics screen update (a new
sample: view built, numbers repainted) with 1,000,000 points collected <= 20 ms, not growing with the
ring where the view does not need it (only the seed's whole-buffer stats do).
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


def fill_runs(store: AnalyticsStore, runs: int, per_run: int) -> None:
    """``runs`` runs of ``per_run`` samples each, alternating two controllers, as the console records."""
    pts = make_points(min(per_run, 20_000), seed=2)
    for r in range(runs):
        run = store.begin_run(("go_to_goal", "pure_pursuit")[r % 2], "square", 1.7e12 + r * 1e6)
        for i in range(per_run):
            p = pts[i % len(pts)]
            store.record(
                DataPoint(1.7e12 + r * 1e6 + i * 100.0, p.x, p.y, p.theta, p.linearVel, p.angularVel,
                          p.distanceError, p.headingError, p.algorithm, p.latencyMs, run)
            )  # fmt: skip
        if r < runs - 1:
            store.end_run("completed", 1.7e12 + r * 1e6 + per_run * 100.0, 0.1)


def bench_runs(runs: int, per_run: int, repeat: int) -> dict[str, float]:
    """The nine stats of every run and of every algorithm, from scratch (no cached summary)."""
    from arbiter_tui.analytics.runs import RunLog

    store = AnalyticsStore(max_data_points=1000)  # a small ring: the runs keep their samples anyway
    store.start_collection()
    fill_runs(store, runs, per_run)
    log: RunLog = store._runs

    def cold() -> None:
        for run in log._runs:
            run._summary = None
        log._pooled.clear()
        log.summaries()
        log.by_algorithm()

    summaries = store.runs()
    return {
        "runs": runs,
        "per_run": per_run,
        "all_runs_ms": median_seconds(cold, repeat) * 1e3,
        "samples_kept": sum(r.stats.sampleCount for r in summaries),
        "ring": len(store),
    }


def bench_screen(n: int, repeat: int) -> dict[str, float]:
    """The analytics screen with ``n`` points collected (in 100 runs), the app run headless at 100x30.

    * ``view_ms``: building the screen's snapshot after one new sample (``publish_views``): what grows
      with the data;
    * ``update_cpu_ms``: CPU of one update: a new sample, the view built, the numbers and the table
      repainted (the plots are not due: they follow at most once a second);
    * ``plots_cpu_ms``: CPU of one redraw of both plots (series rebuilt, drawn, repainted): what is added
      once a second while samples stream in.
    """
    import asyncio

    from arbiter_tui.link.sim import SimLink
    from arbiter_tui.session import views
    from arbiter_tui.session.settings import Settings
    from arbiter_tui.shell.app import make_app
    from arbiter_tui.shell.widgets.plots import Plot

    store = AnalyticsStore(max_data_points=n)
    store.start_collection()
    fill_runs(store, 100, n // 100)
    period = views.PLOT_PERIOD_S
    settings = Settings(mode="sim", live=False, handle_signals=False, max_points=n)
    app = make_app(settings, SimLink(), store=store)
    out: dict[str, float] = {"n": n}

    def sample(i: int) -> None:
        store.record(DataPoint(1.9e12 + i, 0.1 * i, 0.2, 0.0, 0.5, 0.0, 1.0, 0.0, "go_to_goal", None,
                               store.active_run))  # fmt: skip

    async def run() -> None:
        async with app.run_test(size=(100, 30)) as pilot:
            await pilot.press("2")
            await pilot.pause()
            view, update, plots = [], [], []
            views.PLOT_PERIOD_S = math.inf  # numbers only: a slow update must not make the plots due
            for i in range(repeat):
                sample(i)
                c0, t0 = time.process_time(), time.perf_counter()
                app.refresh_frame(force=True)
                view.append(time.perf_counter() - t0)
                await pilot.pause()  # Textual processes the change and repaints
                update.append(time.process_time() - c0)
            views.PLOT_PERIOD_S = 0.0  # from now on the plots are due at every update
            for i in range(repeat):
                sample(repeat + i)
                c0 = time.process_time()
                app.refresh_frame(force=True)
                await pilot.pause()
                plots.append(time.process_time() - c0)
            views.PLOT_PERIOD_S = period
            assert all(p.draws >= repeat for p in app.screen.query(Plot)), "the plots did not redraw"
            out["view_ms"] = statistics.median(view) * 1e3
            out["update_cpu_ms"] = statistics.median(update) * 1e3
            out["plots_cpu_ms"] = statistics.median(plots) * 1e3 - out["update_cpu_ms"]

    asyncio.run(run())
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[1_000, 100_000, 1_000_000])
    ap.add_argument("--repeat", type=int, default=31, help="timed runs per size (median reported)")
    ap.add_argument("--screen-sizes", type=int, nargs="*", default=[10_000, 1_000_000])
    args = ap.parse_args()
    rows = []
    for n in args.sizes:
        row = bench_size(n, args.repeat)
        rows.append(row)
        print(
            f"n={n:>9,}  stats {row['stats_ms']:8.3f} ms  plain {row['plain_ms']:9.2f} ms  "
            f"x{row['speedup']:7.1f}  {row['bytes_per_point']:6.1f} B/point  agree={row['agrees_with_plain']}"
        )
    runs = bench_runs(100, 10_000, max(5, args.repeat // 3))
    print(
        f"runs: {runs['runs']} x {runs['per_run']:,} samples, every run and algorithm from scratch "
        f"{runs['all_runs_ms']:.1f} ms (ring {runs['ring']}, samples kept {runs['samples_kept']:,})"
    )
    screens = []
    for n in args.screen_sizes:
        row = bench_screen(n, max(5, args.repeat // 3))
        screens.append(row)
        print(
            f"analytics screen, {n:>9,} points: view {row['view_ms']:.1f} ms, update CPU "
            f"{row['update_cpu_ms']:.1f} ms, plots redraw CPU +{row['plots_cpu_ms']:.1f} ms (<= 1/s)"
        )
    print(json.dumps({"bench": "stats", "python": platform.python_version(), "results": rows, "runs": runs,
                      "screen": screens}))  # fmt: skip


if __name__ == "__main__":
    main()
