"""The cores a process may use: its CPUs, capped by every cgroup quota on its path (files on disk)."""

import math
import os

from arbiter_tui.session.cpu_share import cgroup_quota, cores_available


def v1_tree(tmp_path, quotas):
    """A cgroup v1 ``cpu`` hierarchy: ``quotas`` maps a folder (under the mount) to (quota, period)."""
    root = tmp_path / "sys"
    for folder, (quota, period) in quotas.items():
        d = root / "cpu,cpuacct" / folder
        d.mkdir(parents=True, exist_ok=True)
        (d / "cpu.cfs_quota_us").write_text(f"{quota}\n")
        (d / "cpu.cfs_period_us").write_text(f"{period}\n")
    return root


def test_a_quota_anywhere_on_the_path_caps_the_cores(tmp_path):
    root = v1_tree(tmp_path, {"": (-1, 100000), "robot": (50000, 100000), "robot/console": (-1, 100000)})
    proc = tmp_path / "cgroup"
    proc.write_text("12:memory:/robot\n4:cpu,cpuacct:/robot/console\n0::/\n")
    assert cgroup_quota(proc, root) == 0.5  # the parent's half a core caps the child without a quota
    (root / "cpu,cpuacct/robot/console/cpu.cfs_quota_us").write_text("2500")
    (root / "cpu,cpuacct/robot/console/cpu.cfs_period_us").write_text("10000")
    assert cgroup_quota(proc, root) == 0.25  # the smallest on the path
    assert cores_available(proc, root) == 0.25


def test_cgroup_v2_cpu_max(tmp_path):
    root = tmp_path / "sys"
    (root / "user.slice/pi").mkdir(parents=True)
    (root / "cpu.max").write_text("max 100000\n")
    (root / "user.slice/cpu.max").write_text("max 100000\n")
    (root / "user.slice/pi/cpu.max").write_text("150000 100000\n")
    proc = tmp_path / "cgroup"
    proc.write_text("0::/user.slice/pi\n")
    assert cgroup_quota(proc, root) == 1.5
    (root / "user.slice/pi/cpu.max").write_text("max 100000\n")
    assert cgroup_quota(proc, root) == math.inf


def test_no_quota_or_unreadable_files_leave_the_cpus_the_affinity_allows(tmp_path):
    cpus = len(os.sched_getaffinity(0))
    assert cores_available(tmp_path / "absent", tmp_path) == cpus
    proc = tmp_path / "cgroup"
    proc.write_text("garbage\n1:cpu:/gone\n")  # a line of no cgroup, a folder that does not exist
    assert cores_available(proc, tmp_path) == cpus
    root = v1_tree(tmp_path, {"odd": (-1, 100000)})
    (root / "cpu,cpuacct/odd/cpu.cfs_period_us").write_text("not a number")
    proc.write_text("1:cpu,cpuacct:/odd\n")
    assert cgroup_quota(proc, root) == math.inf
