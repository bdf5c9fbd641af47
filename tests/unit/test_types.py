"""The packages type-check: mypy over arbiter_core, arbiter_tui and arbiter_backend with the settings in
pyproject.toml ([tool.mypy]) reports nothing. Its cache (.mypy_cache, beside pyproject.toml) makes a
run after the first take well under a second."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MYPY = Path(sys.executable).with_name("mypy")


def test_the_packages_type_check():
    if not MYPY.exists():
        pytest.skip("mypy is not installed (the [test] extra installs it)")
    try:  # the ROS nodes subclass rclpy's Node: without the [ros] extra (a Pi, a Mac) it is untyped
        import rclpy  # noqa: F401
    except ImportError:
        if not os.environ.get("ARBITER_REQUIRE_ROS"):
            pytest.skip("rclpy is not importable: the ROS nodes cannot be type-checked here")
    r = subprocess.run([str(MYPY)], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and "Success" in r.stdout, r.stdout + r.stderr
