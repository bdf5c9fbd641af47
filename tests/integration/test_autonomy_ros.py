"""The robot-side autonomy as an rclpy node on DDS (``--transport ros --autonomy``): the same run, the
same figures as compare's on a perfect link (test_autonomy.py's check)."""

import pytest

from ..support.backend import start_backend
from ..support.ros import use_test_domain
from .test_autonomy import observe_robot_side

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)


def test_the_autonomy_node_on_dds_drives_what_compare_gives():
    observe_robot_side("stanley", start_backend("--transport", "ros", "--autonomy", timeout=30))
