"""The ROS relay's messages make their rosbridge JSON form on first use (arbiter_backend/ros/bus.py):
a camera whose clients all take CBOR never pays its base64; every reader still sees the whole form."""

import json

import pytest

Image = pytest.importorskip("sensor_msgs.msg").Image
rosbus = pytest.importorskip("arbiter_backend.ros.bus")


@pytest.fixture
def counted(monkeypatch):
    calls = []
    real = rosbus.to_json

    def to_json(msg):
        calls.append(msg)
        return real(msg)

    monkeypatch.setattr(rosbus, "to_json", to_json)
    return calls


def image() -> Image:
    m = Image(height=2, width=2, encoding="rgb8", step=6)
    m.data = bytes(range(12))
    return m


def test_nothing_is_converted_until_read_and_then_once(counted):
    ros = image()
    m = rosbus.RosMessage(ros, 123)
    assert counted == [] and m.ros is ros and m.received_ns == 123
    assert m["encoding"] == "rgb8" and len(counted) == 1
    assert json.loads(json.dumps(m.filled()))["data"] == "AAECAwQFBgcICQoL"  # base64 of bytes 0-11
    assert dict(m) == {**m} == m.copy() and len(counted) == 1


@pytest.mark.parametrize(
    "read",
    [
        lambda m: dict(m),
        lambda m: {**m},
        lambda m: list(m.items()),
        lambda m: m.get("width"),
        lambda m: "width" in m,
        lambda m: len(m),
        lambda m: json.dumps(rosbus.RosBus.json_form(None, m)),  # what the endpoint serialises
    ],
)
def test_every_way_of_reading_sees_the_whole_form(counted, read):
    m = rosbus.RosMessage(image(), 0)
    read(m)
    assert len(counted) == 1
    assert dict.__len__(m) == len(Image.get_fields_and_field_types())  # filled in place
