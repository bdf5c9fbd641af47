"""``--transport ros`` where rclpy does not import (issue 46, item 5): one line with the whole fix on
stderr and exit 2, before anything starts, from the console as from the backend, in the same words."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from arbiter_core.rosenv import ROS_HINT

ROOT = Path(__file__).resolve().parents[2]  # this tree's packages first, then whatever the run had
WHY = "ImportError: no rclpy in this test"


def run_without_rclpy(tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """``python -m ARGS`` with an ``rclpy`` first on the path whose import fails."""
    fake = tmp_path / "no_ros" / "rclpy"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text(f"raise ImportError({WHY.split(': ', 1)[1]!r})\n")
    path = os.pathsep.join(p for p in (str(fake.parent), str(ROOT), os.environ.get("PYTHONPATH")) if p)
    env = {**os.environ, "PYTHONPATH": path, "XDG_CONFIG_HOME": str(tmp_path / "config")}
    try:
        return subprocess.run(
            [sys.executable, "-m", *args],
            capture_output=True,
            text=True,
            timeout=30,
            env=env,
            stdin=subprocess.DEVNULL,
            cwd=tmp_path,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"{args[0]} was still running after 30 s: it started instead of refusing")


@pytest.mark.parametrize(
    ("module", "says"),
    [
        ("arbiter_tui.cli", f"arbiter-tui: --transport ros: {ROS_HINT} ({WHY})"),
        ("arbiter_backend.cli", f"arbiter-backend: {ROS_HINT} ({WHY})"),
    ],
)
def test_transport_ros_without_rclpy_is_one_line_with_the_whole_fix(tmp_path: Path, module: str, says: str):
    r = run_without_rclpy(tmp_path, module, "--transport", "ros", "--log-file", str(tmp_path / "log"))
    assert r.returncode == 2, (r.returncode, r.stderr[-2000:])
    assert r.stderr.splitlines() == [says]
    assert r.stdout == ""  # no frame of a console: it never started


def test_the_fix_is_not_asked_for_where_the_transport_does_not_apply(tmp_path: Path, monkeypatch):
    """--transport is the embedded backend's: in client-side simulation (or --connect) rclpy is not
    needed, so its absence refuses nothing and the console runs."""
    import arbiter_tui.shell.app as shell_app
    from arbiter_tui import launch

    ran: list[str] = []

    class App:
        def run(self) -> None:
            ran.append("run")

        def close_link(self) -> None:
            ran.append("closed")

    monkeypatch.setattr(launch, "rclpy_missing", lambda: f"{ROS_HINT} ({WHY})")
    monkeypatch.setattr(shell_app, "make_app", lambda *a, **k: App())
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    assert launch.run_app(["--sim", "--transport", "ros", "--log-file", str(tmp_path / "log")]) == 0
    assert ran == ["run", "closed"]
