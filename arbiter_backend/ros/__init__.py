"""The ROS 2 transport: the tracker and simulator as rclpy nodes, the rosbridge endpoint relaying to DDS.

Everything that imports ``rclpy`` lives in this package, and nothing outside it
imports this package at module level, so the rest of the product runs without a
ROS install.
"""

from __future__ import annotations

ROS_HINT = (
    "rclpy is not importable: pip install 'arbiter-tui[ros]' (x86_64, Python 3.11/3.12) "
    "or source /opt/ros/<distro>/setup.bash"
)


def rclpy_available() -> str | None:
    """None when rclpy imports; otherwise the reason it does not."""
    try:
        import rclpy  # noqa: F401
    except Exception as exc:  # ImportError, or a broken install raising anything at import
        return f"{type(exc).__name__}: {exc}"
    return None
