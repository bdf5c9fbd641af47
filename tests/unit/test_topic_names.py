"""Namespaces and topic names resolve the ROS way; bad ones are one-line errors."""

import pytest

from arbiter_core.topics import TopicNameError, namespace, resolve


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
