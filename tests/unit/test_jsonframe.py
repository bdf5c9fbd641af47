"""The spliced JSON of a frame is the text json.dumps makes, only faster for long base64 strings."""

import base64
import json
import math
import os

import pytest

from arbiter_backend import jsonframe
from arbiter_backend.jsonframe import SPLICE_MIN, Base64Text


def _plain(obj):
    return json.dumps(obj, separators=(",", ":"), allow_nan=False)


def _b64(n: int) -> Base64Text:
    return Base64Text(base64.b64encode(os.urandom(n)).decode("ascii"))


def test_a_camera_frame_is_the_same_text():
    image = {"header": {"frame_id": "cam"}, "height": 480, "width": 640, "data": _b64(640 * 480 * 3)}
    frame = {"op": "publish", "topic": "/image", "msg": image}
    assert jsonframe.dumps(frame) == _plain(frame)


def test_several_long_strings_nested_in_dicts_and_lists_keep_their_places():
    a, b, c = _b64(SPLICE_MIN), _b64(SPLICE_MIN + 7), _b64(3 * SPLICE_MIN)
    msg = {"first": {"data": a}, "clouds": [{"data": b, "n": 1}, {"data": c}], "after": 'x"y'}
    text = jsonframe.dumps(msg)
    assert text == _plain(msg)
    assert json.loads(text)["clouds"][1]["data"] == c


def test_the_message_itself_is_not_changed():
    data = _b64(SPLICE_MIN * 2)
    msg = {"data": data, "inner": {"data": data}}
    jsonframe.dumps(msg)
    assert msg["data"] is data and msg["inner"]["data"] is data


def test_only_base64_text_is_spliced_other_long_strings_are_escaped():
    raw = '"quoted"\n\\' * SPLICE_MIN  # a plain string: json.dumps escapes it
    msg = {"text": raw, "short": Base64Text("QUJD"), "numbers": [1.5, 2, 3]}
    text = jsonframe.dumps(msg)
    assert text == _plain(msg)
    assert json.loads(text)["text"] == raw


def test_non_finite_numbers_are_still_refused():
    with pytest.raises(ValueError):
        jsonframe.dumps({"data": _b64(SPLICE_MIN), "x": math.nan})


def test_the_ros_converter_marks_its_base64():
    pytest.importorskip("sensor_msgs.msg")
    from sensor_msgs.msg import Image

    from arbiter_backend.ros.convert import to_json

    image = Image(height=2, width=2, encoding="rgb8", step=6)
    image.data = bytes(range(12))
    data = to_json(image)["data"]
    assert isinstance(data, Base64Text)
    assert base64.b64decode(data) == bytes(range(12))
