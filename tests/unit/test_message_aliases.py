"""What a published message may say, as rosbridge_suite's ``message_conversion`` takes it, the same on
both transports: the embedded one's checker (``arbiter_core.msgtypes``) and the ROS one's conversion
(``arbiter_backend.ros.convert``, where rclpy is installed). Each case is one of message_conversion's
rules (``_to_time_inst``, ``_to_object_inst``, ``_to_primitive_inst``): ROS 1's ``secs``/``nsecs`` for a
Time's ``sec``/``nanosec`` (roslibpy's ``Time`` sends them), ``"now"``, a Header given without a stamp
stamped now, missing fields their defaults, an int for a float; and what it refuses."""

import importlib.util
import time

import pytest

from arbiter_core.msgtypes import MessageError, check_message

HAS_RCLPY = importlib.util.find_spec("rclpy") is not None
NOW = object()  # the case expects the current time here


def embedded(type_name: str, msg):
    return check_message(type_name, msg)


def ros(type_name: str, msg):
    convert = pytest.importorskip("arbiter_backend.ros.convert")
    return convert.to_json(convert.to_ros(convert.message_class(type_name), msg))


TRANSPORTS = [pytest.param(embedded, id="embedded"), pytest.param(ros, id="ros")]
ZERO = {"sec": 0, "nanosec": 0}

ACCEPTED = [
    # roslibpy's Header(stamp=Time.now()): ROS 1's names
    ("std_msgs/msg/Header", {"stamp": {"secs": 5, "nsecs": 7}, "frame_id": "map"},
     {"stamp": {"sec": 5, "nanosec": 7}, "frame_id": "map"}),
    ("builtin_interfaces/msg/Time", {"secs": 12}, {"sec": 12, "nanosec": 0}),
    ("builtin_interfaces/msg/Time", {"nsecs": 3}, {"sec": 0, "nanosec": 3}),
    # both spellings: the ROS 2 name wins (message_conversion tries sec first)
    ("builtin_interfaces/msg/Time", {"sec": 1, "secs": 9, "nanosec": 2, "nsecs": 8},
     {"sec": 1, "nanosec": 2}),
    ("builtin_interfaces/msg/Time", "now", NOW),
    ("std_msgs/msg/Header", {"stamp": "now"}, {"stamp": NOW, "frame_id": ""}),
    # a header given without a stamp is stamped now; a message without a header keeps a zero stamp
    ("std_msgs/msg/Header", {"frame_id": "odom"}, {"stamp": NOW, "frame_id": "odom"}),
    ("geometry_msgs/msg/TwistStamped", {"header": {}}, {"header": {"stamp": NOW, "frame_id": ""},
     "twist": {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}}),
    ("geometry_msgs/msg/TwistStamped", {"twist": {"linear": {"x": 1}}}, {"header": {"stamp": ZERO,
     "frame_id": ""}, "twist": {"linear": {"x": 1.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0,
     "z": 0.0}}}),
    # missing fields: their defaults (a quaternion's w is 1); an int for a float
    ("geometry_msgs/msg/Quaternion", {"z": 1}, {"x": 0.0, "y": 0.0, "z": 1.0, "w": 1.0}),
    ("std_msgs/msg/String", {}, {"data": ""}),
]  # fmt: skip

REFUSED = [
    ("std_msgs/msg/Header", {"stamp": {"secs": 1.5}}, "integer"),  # a float for an int
    ("builtin_interfaces/msg/Time", {"sec": 2.0}, "integer"),
    ("builtin_interfaces/msg/Time", {"sec": True}, "integer|number"),  # a bool for an int
    ("builtin_interfaces/msg/Time", {"nanosec": -1}, "range"),
    ("builtin_interfaces/msg/Time", "later", "object"),
    ("std_msgs/msg/Header", {"stamp": {"sec": 1, "frac": 0}}, "unknown field 'frac'"),
    ("std_msgs/msg/Header", {"seq": 4}, "unknown field 'seq'"),  # ROS 1's header field: not in ROS 2
    ("geometry_msgs/msg/Twist", {"linear": {"x": None}}, "number"),  # null
    ("geometry_msgs/msg/Twist", {"linear": {"x": "1"}}, "number"),  # a string for a number
    ("std_msgs/msg/String", {"data": 5}, "string"),
]


def same(got, expected, before_ns: int, after_ns: int) -> bool:
    if expected is NOW:
        ns = got["sec"] * 1_000_000_000 + got["nanosec"]
        return before_ns <= ns <= after_ns
    if isinstance(expected, dict):
        keys_same = set(got) == set(expected)
        return keys_same and all(same(got[k], v, before_ns, after_ns) for k, v in expected.items())
    return got == expected and type(got) is type(expected)


@pytest.mark.parametrize("convert", TRANSPORTS)
@pytest.mark.parametrize(("type_name", "msg", "expected"), ACCEPTED)
def test_what_rosbridge_accepts_is_accepted_the_same_way(convert, type_name, msg, expected):
    before = time.time_ns()
    got = convert(type_name, msg)
    assert same(got, expected, before, time.time_ns()), got


@pytest.mark.parametrize("convert", TRANSPORTS)
@pytest.mark.parametrize(("type_name", "msg", "said"), REFUSED)
def test_what_rosbridge_refuses_is_refused_with_the_field_named(convert, type_name, msg, said):
    with pytest.raises(MessageError, match=said):
        convert(type_name, msg)


def test_a_header_stamp_given_in_part_keeps_the_rest_of_now_as_rosbridge():
    """message_conversion stamps a Header now, then sets the stamp's fields given: ``sec`` alone keeps
    now's ``nanosec``."""
    got = check_message("std_msgs/msg/Header", {"stamp": {"secs": 7}}, clock=lambda: 3_000_000_042)
    assert got["stamp"] == {"sec": 7, "nanosec": 42}
