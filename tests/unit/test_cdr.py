"""A nav_msgs/Path's positions read straight from its CDR bytes (analytics/cdr.py), against rosbags'
general decoder: both byte orders, any frame id, every pose count; irregular layouts refused (None)."""

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from arbiter_tui.analytics.cdr import path_xy

TS = get_typestore(Stores.ROS2_KILTED)
T = TS.types


def path(points: np.ndarray, frames: list[str]) -> object:
    def header(frame: str) -> object:
        return T["std_msgs/msg/Header"](
            stamp=T["builtin_interfaces/msg/Time"](sec=7, nanosec=9), frame_id=frame
        )

    def pose(x: float, y: float) -> object:
        p = T["geometry_msgs/msg/Point"](x=x, y=y, z=0.5)
        q = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.3, w=0.95)
        return T["geometry_msgs/msg/Pose"](position=p, orientation=q)

    poses = [T["geometry_msgs/msg/PoseStamped"](header=header(f), pose=pose(x, y)) for (x, y), f in
             zip(points, frames, strict=True)]  # fmt: skip
    return T["nav_msgs/msg/Path"](header=header("map"), poses=poses)


@pytest.mark.parametrize("little_endian", [True, False])
@pytest.mark.parametrize("frame", ["", "map", "odom", "a_longer_frame"])
@pytest.mark.parametrize("count", [0, 1, 2, 3, 50])
def test_the_positions_equal_the_general_decoders(little_endian: bool, frame: str, count: int):
    points = np.random.default_rng(count).normal(size=(count, 2)) * 100
    raw = TS.serialize_cdr(path(points, [frame] * count), "nav_msgs/msg/Path", little_endian=little_endian)
    decoded = TS.deserialize_cdr(raw, "nav_msgs/msg/Path")
    expected = np.array([(p.pose.position.x, p.pose.position.y) for p in decoded.poses]).reshape(-1, 2)
    got = path_xy(raw)
    assert got is not None and got.shape == (count, 2) and np.array_equal(got, expected)


def test_irregular_or_damaged_bytes_are_refused_not_misread():
    points = np.arange(8.0).reshape(4, 2)
    mixed = TS.serialize_cdr(path(points, ["map", "odom_x", "map", "map"]), "nav_msgs/msg/Path")
    assert path_xy(mixed) is None  # frame ids of different lengths: decode it the general way
    raw = bytes(TS.serialize_cdr(path(points, ["map"] * 4), "nav_msgs/msg/Path"))
    assert path_xy(raw[:-8]) is None and path_xy(raw + b"\0" * 8) is None  # cut short, or trailing bytes
    assert path_xy(b"") is None and path_xy(b"\x00\x01\x00\x00") is None
    assert path_xy(b"\x01\x01" + raw[2:]) is None  # not plain CDR
