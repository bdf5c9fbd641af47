"""How much CPU this process may use: the CPUs it may run on, capped by its cgroup's CPU quota.

A Raspberry Pi has four cores, and a sweep child there gets a core of its own. A container or a
systemd unit with ``CPUQuota=`` (or bench/pi.py's Pi stand-in at 25 % of a core) may have a quarter
of one, which the console and every child it starts share: a child that computes spends the quota the
control loop needs, ``nice`` or not (``nice`` only orders what shares a quota).

Read from ``/proc/self/cgroup`` and the cgroup file system: cgroup v1 ``cpu.cfs_quota_us`` /
``cpu.cfs_period_us`` and v2 ``cpu.max``, along the whole path up to the root (a parent's quota caps
its children). Anything unreadable counts as no quota: the answer is then the CPUs the affinity mask
allows (``os.sched_getaffinity``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path, PurePosixPath

CGROUP_ROOT = Path("/sys/fs/cgroup")
SPARE_CORES = 2.0  # a console with fewer has no core to spare: the UI and any child take the robot's
PROC_CGROUP = Path("/proc/self/cgroup")


def cores_available(proc_cgroup: Path = PROC_CGROUP, root: Path = CGROUP_ROOT) -> float:
    """The cores this process may use at most (0.25: a quarter of one core's time)."""
    try:
        cpus = float(len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        cpus = float(os.cpu_count() or 1)
    return min(cpus, cgroup_quota(proc_cgroup, root))


def cgroup_quota(proc_cgroup: Path = PROC_CGROUP, root: Path = CGROUP_ROOT) -> float:
    """The smallest CPU quota on this process's cgroup path, in cores (``inf``: none found, or a file
    system that cannot be read)."""
    try:
        return _quota(proc_cgroup.read_text().splitlines(), root)
    except OSError:  # e.g. a cgroup mount that refuses to be looked at (EACCES)
        return math.inf


def _quota(lines: list[str], root: Path) -> float:
    quota = math.inf
    for line in lines:
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        _hierarchy, controllers, path = parts
        if controllers == "":  # cgroup v2: one unified hierarchy
            mounts = (root / "unified", root) if (root / "unified").is_dir() else (root,)
            for mount in mounts:
                quota = min(quota, _along(mount, path, _v2))
        elif "cpu" in controllers.split(","):
            mount = root / controllers
            if not mount.is_dir():
                mount = root / "cpu"
            quota = min(quota, _along(mount, path, _v1))
    return quota


def _along(mount: Path, path: str, read: Callable[[Path], float]) -> float:
    """The smallest quota from ``mount/path`` up to ``mount``."""
    quota = math.inf
    here = PurePosixPath(path)
    for level in (here, *here.parents):
        folder = mount / str(level).lstrip("/")
        if folder.is_dir():
            quota = min(quota, read(folder))
    return quota


def _v1(folder: Path) -> float:
    try:
        quota = int((folder / "cpu.cfs_quota_us").read_text())
        period = int((folder / "cpu.cfs_period_us").read_text())
    except (OSError, ValueError):
        return math.inf
    return quota / period if quota > 0 and period > 0 else math.inf  # -1: no quota


def _v2(folder: Path) -> float:
    try:
        quota, period = (folder / "cpu.max").read_text().split()[:2]
        return int(quota) / int(period) if quota != "max" and int(period) > 0 else math.inf
    except (OSError, ValueError):
        return math.inf
