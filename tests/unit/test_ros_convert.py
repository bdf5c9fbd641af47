"""JSON <-> ROS conversion by introspection, over every message type of the installed packages."""

import importlib
import inspect
import json

import pytest

from arbiter_core.msgtypes import MessageError

from ..support.ros import Odometry  # noqa: F401  (skips the module without rclpy)

convert = importlib.import_module("arbiter_backend.ros.convert")

PACKAGES = ("std_msgs", "geometry_msgs", "nav_msgs", "builtin_interfaces")


def all_message_classes():
    for pkg in PACKAGES:
        module = importlib.import_module(f"{pkg}.msg")
        for name, cls in inspect.getmembers(module, inspect.isclass):
            if hasattr(cls, "get_fields_and_field_types") and not name.startswith("_"):
                yield f"{pkg}/msg/{name}", cls


CLASSES = list(all_message_classes())


def test_the_installed_packages_hold_many_types():
    assert len(CLASSES) > 60


@pytest.mark.parametrize(("name", "cls"), CLASSES, ids=[n for n, _ in CLASSES])
def test_every_type_round_trips_and_is_strict_json(name, cls):
    assert convert.message_class(name) is cls
    assert convert.type_name_of(cls) == name
    data = convert.to_json(cls())
    json.dumps(data, allow_nan=False)
    assert convert.to_json(convert.to_ros(cls, json.loads(json.dumps(data)))) == data


def test_values_survive_both_ways_and_bytes_are_base64():
    from std_msgs.msg import ByteMultiArray, UInt8MultiArray

    odom = {
        "header": {"stamp": {"sec": 5, "nanosec": 7}, "frame_id": "odom"},
        "pose": {"pose": {"position": {"x": 1, "y": -2.5}}, "covariance": [float(i) for i in range(36)]},
    }
    msg = convert.to_ros(convert.message_class("nav_msgs/Odometry"), odom)
    assert msg.pose.pose.position.x == 1.0 and msg.pose.pose.orientation.w == 1.0
    back = convert.to_json(msg)
    assert back["pose"]["covariance"][35] == 35.0 and back["header"]["stamp"] == {"sec": 5, "nanosec": 7}
    u = convert.to_ros(UInt8MultiArray, {"data": "AAH/"})
    assert list(u.data) == [0, 1, 255] and convert.to_json(u)["data"] == "AAH/"
    b = convert.to_ros(ByteMultiArray, {"data": [1, 2, 255]})
    assert convert.to_json(b)["data"] == "AQL/"


def test_non_finite_floats_leave_as_null():
    from geometry_msgs.msg import Vector3

    assert convert.to_json(Vector3(x=float("nan"), y=float("inf"), z=1.0)) == {"x": None, "y": None, "z": 1.0}


@pytest.mark.parametrize(
    ("type_name", "data", "expect"),
    [
        ("std_msgs/String", {"data": 5}, "msg.data must be a string"),
        ("std_msgs/String", {"nope": ""}, "unknown field 'nope'"),
        ("std_msgs/String", [], "must be an object"),
        ("geometry_msgs/Twist", {"linear": {"x": True}}, "must be a number"),
        ("geometry_msgs/Twist", {"linear": {"x": 10**400}}, "too large"),
        ("geometry_msgs/Twist", {"linear": {"x": 1e400}}, "must be finite"),
        ("nav_msgs/Odometry", {"pose": {"covariance": [0.0] * 3}}, "exactly 36 elements"),
        ("builtin_interfaces/Time", {"sec": 2**40}, "out of range for int32"),
        ("builtin_interfaces/Time", {"nanosec": -1}, "out of range for uint32"),
        ("builtin_interfaces/Time", {"sec": 1.5}, "must be an integer"),
        ("std_msgs/UInt8MultiArray", {"data": "!!!"}, "base64"),
        ("std_msgs/Bool", {"data": 1}, "true or false"),
        ("no_such_pkg/Thing", {}, "not installed"),
        ("not a type", {}, "invalid message type name"),
    ],
)
def test_bad_messages_name_the_field(type_name, data, expect):
    with pytest.raises(MessageError, match=expect):
        convert.to_ros(convert.message_class(type_name), data)


# the messages rosidl generates for services and actions travel on topics of their own: a service's
# ``_service_event`` (introspection on) and an action's ``_action/feedback``; their classes live in the
# ``srv``/``action`` modules, an action's Goal/Result/Feedback/FeedbackMessage on the action's class
INTERFACE_MESSAGES = [
    ("std_srvs/srv/Trigger_Event", "std_srvs.srv", "Trigger_Event"),
    ("std_srvs/srv/Trigger_Request", "std_srvs.srv", "Trigger_Request"),
    ("test_msgs/action/Fibonacci_FeedbackMessage", "test_msgs.action", "Fibonacci_FeedbackMessage"),
    ("test_msgs/action/Fibonacci_Goal", "test_msgs.action", "Fibonacci_Goal"),
    ("test_msgs/action/Fibonacci_SendGoal_Event", "test_msgs.action", "Fibonacci_SendGoal_Event"),
]


@pytest.mark.parametrize(("name", "module", "cls_name"), INTERFACE_MESSAGES)
def test_the_messages_of_services_and_actions_are_message_types(name, module, cls_name):
    cls = convert.message_class(name)
    assert cls.__module__.startswith(module) and cls.__name__ == cls_name
    assert convert.type_name_of(cls) == name
    data = convert.to_json(cls())  # nested srv/action messages (a Trigger_Event's request) resolve too
    assert convert.to_json(convert.to_ros(cls, json.loads(json.dumps(data)))) == data


@pytest.mark.parametrize(
    ("name", "words"),
    [
        ("std_srvs/srv/Trigger", "invalid message type name"),  # a service, not a message
        ("test_msgs/action/Fibonacci", "invalid message type name"),
        ("test_msgs/action/Fibonacci_Bogus", "invalid message type name"),
        ("std_srvs/srv/Trigger_FeedbackMessage", "invalid message type name"),  # an action's part, on a srv
        ("no_such_pkg/srv/X_Event", "message type no_such_pkg/srv/X_Event is not installed"),
        ("std_srvs/srv/NoSuch_Event", "is not installed"),
    ],
)
def test_what_is_not_a_message_of_a_service_or_action_is_refused(name, words):
    with pytest.raises(MessageError, match=words):
        convert.message_class(name)
