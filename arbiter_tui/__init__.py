"""arbiter-tui: terminal teleop console and analytics/latency monitor for ROS 2 robots."""

__version__ = "0.1.0"
