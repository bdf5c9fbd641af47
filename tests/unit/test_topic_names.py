"""Namespaces and topic names resolve the ROS way; bad ones are one-line errors."""

import pytest

from arbiter_core.topics import TopicNameError, is_command, namespace, resolve


@pytest.mark.parametrize(
    ("ns", "expected"),
    [(None, ""), ("", ""), ("/", ""), ("robot1", "/robot1"), ("/fleet/robot_2", "/fleet/robot_2")],
)
def test_namespaces(ns, expected):
    assert namespace(ns) == expected


@pytest.mark.parametrize(
    ("name", "ns", "expected"),
    [
        ("odom", "", "/odom"),
        ("odom", "/robot1", "/robot1/odom"),
        ("diff_drive_controller/odom", "/robot1", "/robot1/diff_drive_controller/odom"),
        ("/odom", "/robot1", "/odom"),  # absolute: as given
        ("/robot9/odom", "", "/robot9/odom"),
    ],
)
def test_relative_names_resolve_under_the_namespace(name, ns, expected):
    assert resolve(name, ns) == expected


@pytest.mark.parametrize("bad", ["1robot", "/robot 1", "/a//b", "/a/", "/a-b"])
def test_bad_namespaces(bad):
    with pytest.raises(TopicNameError):
        namespace(bad)


@pytest.mark.parametrize("bad", ["", "/", "~/odom", "odom/", "a//b", "odom.x"])
def test_bad_topic_names(bad):
    with pytest.raises(TopicNameError) as err:
        resolve(bad, "/robot1", what="odom-topic")
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("topic", "type_name", "command"),
    [
        ("/stamped_cmd_vel", "std_msgs/msg/String", True),  # our stamped envelope is a String
        ("/robot1/cmd_vel_measured", "geometry_msgs/msg/TwistStamped", True),
        ("/robot1/cmd_vel", "std_msgs/msg/String", True),
        ("/teleop/out", "geometry_msgs/msg/Twist", True),  # a Twist is a command, whatever its name
        ("/cmd_vel_mux/status", "std_msgs/msg/String", False),
        ("/chatter", "std_msgs/msg/String", False),
        ("/map", "nav_msgs/msg/OccupancyGrid", False),
    ],
)
def test_velocity_commands_are_known_by_name_or_type(topic, type_name, command):
    assert is_command(topic, type_name) is command
