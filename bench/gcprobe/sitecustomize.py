"""Garbage collections as a process sees them: put this folder on PYTHONPATH and every Python process
started with it writes one line per generation-2 collection (and per collection over 5 ms of wall time)
to /tmp/arbiter-gc-PID.log: monotonic time, generation, wall ms, objects collected. For example:

    sudo python bench/pi.py --size 200x60 --no-key-to-wire --screens control,analytics \\
        --pythonpath "$PWD:$PWD/bench/gcprobe"
    grep gen2 /tmp/arbiter-gc-*.log
"""

import gc
import os
import time

_started: dict[str, float] = {}
_log = open(f"/tmp/arbiter-gc-{os.getpid()}.log", "a", buffering=1)  # noqa: SIM115 (lives as the process)


def _timed(phase: str, info: dict) -> None:
    if phase == "start":
        _started["at"] = time.perf_counter()
        return
    wall_ms = (time.perf_counter() - _started.get("at", time.perf_counter())) * 1e3
    if info["generation"] == 2 or wall_ms > 5.0:
        gen, collected = info["generation"], info["collected"]
        _log.write(f"{time.monotonic():.3f} gen{gen} {wall_ms:.1f} ms {collected} collected\n")


gc.callbacks.append(_timed)
