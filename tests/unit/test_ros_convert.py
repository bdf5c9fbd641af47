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
