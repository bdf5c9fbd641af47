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


@pytest.mark.parametrize("bad", ["", "/", "~/odom", "odom/", "a//b", "odom.x", "{foo}/x"])
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


# -- the names a rosbridge client gives: rosbridge_suite's node hands each to rclpy, which expands it with
# rcl_expand_topic_name for the node's name and namespace; ours must give the same name or refuse it
CLIENT_NAMES = [
    "odom", "/odom", "rosapi/topics", "/rosapi/topics", "diff_drive_controller/odom", "~", "~/x",
    "~x", "{node}/x", "{ns}/x", "{namespace}/x", "x{node}", "_hidden/x", "a__b", "a/_b",
    # refused by both
    "", "/", "a/", "1a", "/a/1b", "a-b", "a/~", "{foo}", "a//b", "/a//b", "a b", "{node", "~foo", "~ab",
]  # fmt: skip


def rclpy_resolves(name: str, node: str, ns: str) -> str | None:
    """What a node ``node`` in ``ns`` (rclpy's form: ``/`` for the root) makes of ``name`` when it
    creates a publisher, service or action (expanded, then validated as a full name); None: refused."""
    expand = pytest.importorskip("rclpy.expand_topic_name").expand_topic_name
    from rclpy.validate_full_topic_name import validate_full_topic_name

    try:
        full = expand(name, node, ns)
        validate_full_topic_name(full)
    except Exception:
        return None
    return str(full)


@pytest.mark.parametrize("ns", ["", "/robot1", "/fleet/robot_2"])
@pytest.mark.parametrize("name", CLIENT_NAMES)
def test_a_clients_name_resolves_as_rclpy_resolves_it_for_the_bridge_node(name, ns):
    expected = rclpy_resolves(name, "arbiter_bridge", ns or "/")
    if expected is None:
        with pytest.raises(TopicNameError) as err:
            resolve(name, ns, node="arbiter_bridge")
        assert "\n" not in str(err.value)
    else:
        assert resolve(name, ns, node="arbiter_bridge") == expected


@pytest.mark.parametrize("name", ["~", "~/x", "{node}/x"])
def test_without_a_node_a_private_name_is_refused(name):
    with pytest.raises(TopicNameError, match="node"):
        resolve(name, "/robot1")
