"""Shared by the benchmark scripts: a backend on free ports, percentiles by the product's rule, output."""

from __future__ import annotations

import json
import os
import platform
import socket
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from arbiter_core import stats


def pct(values, q: float) -> float | None:
    return round(stats.percentile(values, q), 4) if len(values) else None


def machine() -> dict:
    return {
        "python": platform.python_version(),
        "cpus": os.cpu_count(),
        "machine": platform.machine(),
        "date": time.strftime("%Y-%m-%d"),
    }


def emit(result: dict) -> None:
    """The last line of every benchmark: one JSON object."""
    print(json.dumps({**result, "machine": machine()}, separators=(",", ":")), flush=True)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def sleep_until(t: float) -> None:
    while True:
        d = t - time.monotonic()
        if d <= 0:
            return
        time.sleep(d if d > 0.002 else 0)


def rss_kb(pid: int) -> int | None:
    """Resident memory of a process (VmRSS, KiB); None once it is gone."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


PACKAGES = ("arbiter_core", "arbiter_tui", "arbiter_backend")


def compile_checkout(pythonpath: str | None = None) -> None:
    """Byte-compile the checkout whose code a bench runs (this one by default), as installing a package
    does: with PYTHONDONTWRITEBYTECODE set (as on the machines these figures come from) an editable
    checkout is compiled from source at every launch, ~50 ms of a first frame that no installed copy
    pays, while the bare Textual app it is compared with imports a compiled Textual. ``pythonpath``:
    the bench's ``--pythonpath`` (each of its folders that holds one of the packages)."""
    import compileall

    roots = pythonpath.split(os.pathsep) if pythonpath else [str(Path(__file__).resolve().parent.parent)]
    for root in roots:
        for name in PACKAGES:
            if (Path(root) / name).is_dir():
                compileall.compile_dir(Path(root) / name, quiet=1, workers=0)
