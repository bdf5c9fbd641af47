"""Garbage collections as a process sees them: put this folder on PYTHONPATH and every Python process
started with it writes one line per generation-2 collection (and per collection over 5 ms of wall time)
to /tmp/arbiter-gc-PID.log: monotonic time, generation, wall ms, objects collected. For example:

    sudo python bench/pi.py --size 200x60 --no-key-to-wire --screens control,analytics \\
        --pythonpath "$PWD:$PWD/bench/gcprobe"
    grep gen2 /tmp/arbiter-gc-*.log

With ``ARBITER_GC_CENSUS=N`` it also writes, before each of the first N generation-2 collections, what
that collection is about to walk: the number of objects in the old generation (not frozen) and the 12
most common types among them (counting costs a walk of its own, so it perturbs the timings after it).
"""

import collections
import gc
import os
import time

_started: dict[str, float] = {}
_log = open(f"/tmp/arbiter-gc-{os.getpid()}.log", "a", buffering=1)  # noqa: SIM115 (lives as the process)
_census = [int(os.environ.get("ARBITER_GC_CENSUS", "0"))]


def _count_old_generation() -> None:
    old = gc.get_objects(2)
    kinds = collections.Counter(f"{type(o).__module__}.{type(o).__qualname__}" for o in old)
    top = ", ".join(f"{name} {n}" for name, n in kinds.most_common(12))
    _log.write(f"{time.monotonic():.3f} census {len(old)} old, {gc.get_freeze_count()} frozen: {top}\n")
    del old


def _timed(phase: str, info: dict) -> None:
    if phase == "start":
        if info["generation"] == 2 and _census[0] > 0:
            _census[0] -= 1
            _count_old_generation()
        _started["at"] = time.perf_counter()
        return
    wall_ms = (time.perf_counter() - _started.get("at", time.perf_counter())) * 1e3
    if info["generation"] == 2 or wall_ms > 5.0:
        gen, collected = info["generation"], info["collected"]
        _log.write(f"{time.monotonic():.3f} gen{gen} {wall_ms:.1f} ms {collected} collected\n")


gc.callbacks.append(_timed)

if os.environ.get("ARBITER_GC_THRESHOLD"):  # e.g. 50000,10,10: try the collector's thresholds
    gc.set_threshold(*(int(n) for n in os.environ["ARBITER_GC_THRESHOLD"].split(",")))

if os.environ.get("ARBITER_GC_FROZEN"):  # every N s: objects frozen, tracked, and the process's RSS
    import threading

    def _frozen_log(every: float = float(os.environ["ARBITER_GC_FROZEN"])) -> None:
        while True:
            time.sleep(every)
            with open("/proc/self/statm") as statm:
                rss_kb = int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") // 1024
            _log.write(f"{time.monotonic():.3f} frozen {gc.get_freeze_count()} tracked "
                       f"{len(gc.get_objects())} rss_kb {rss_kb}\n")

    threading.Thread(target=_frozen_log, daemon=True, name="gcprobe").start()
