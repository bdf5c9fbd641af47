"""Whether the ROS 2 transport can run here: one check and one fix text for every command that offers
``--transport ros`` (``arbiter-backend``, and ``arbiter-tui`` before it starts the backend)."""

from __future__ import annotations

import importlib

ROS_HINT = (
    "rclpy is not importable: pip install 'arbiter-tui[ros]' (x86_64, Python 3.11/3.12) "
    "or source /opt/ros/<distro>/setup.bash"
)


def rclpy_missing() -> str | None:
    """None when rclpy imports; otherwise one line: the fix, then why the import failed."""
    try:
        # probed by name, never used here: arbiter_core imports no ROS (its import contract)
        importlib.import_module("rclpy")
    except Exception as exc:  # ImportError, or a broken install raising anything at import
        return f"{ROS_HINT} ({type(exc).__name__}: {exc})"
    return None
