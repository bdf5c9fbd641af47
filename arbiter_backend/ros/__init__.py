"""The ROS 2 transport: the tracker and simulator as rclpy nodes, the rosbridge endpoint relaying to DDS.

Everything that uses ``rclpy`` lives in this package, and nothing outside it
imports this package at module level, so the rest of the product runs without a
ROS install (``arbiter_core.rosenv`` only tries the import, to say how to fix it).
"""

from __future__ import annotations
