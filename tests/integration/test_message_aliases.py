"""Every field alias and default rosbridge_suite's ``message_conversion.py`` accepts on a publish, checked
on what a subscriber receives: a real rclpy subscriber on ``--transport ros``, a WebSocket subscriber of
the embedded bus (there only for the types the embedded transport knows; it passes others through).

What rosbridge_suite accepts (``rosbridge_library/internal/message_conversion.py``, ``_to_inst``):
- ``builtin_interfaces/Time`` and ``Duration``: ``secs``/``nsecs`` for ``sec``/``nanosec``; a Time of
  ``"now"`` is the current time;
- a field left out keeps its type's default (a Quaternion's ``w`` is 1.0);
- a ``std_msgs/Header`` that is given is stamped with the current time first (then its own ``stamp``,
  if any, replaces it); a header left out keeps the zero stamp;
- an integer for a float, alone or in a float array;
- an integer for an ``octet`` (``byte``) and for a ``char``;
- ``uint8[]``: base64 text, or a list of integers.
"""

from __future__ import annotations

import asyncio
import base64
import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import aiohttp
import pytest

from arbiter_core import msgtypes

from ..support.backend import start_backend, wait_for

NOW = "now"  # in an expectation: a stamp within the publish's wall-clock span


@dataclass(frozen=True)
class Case:
    name: str
    type: str
    msg: dict[str, Any]
    want: dict[str, Any]  # what the subscriber gets, field by field (only these fields are compared)


CASES = [
    Case(
        "time_secs_nsecs",
        "geometry_msgs/msg/TwistStamped",
        {"header": {"stamp": {"secs": 5, "nsecs": 7}, "frame_id": "a"}},
        {"header": {"stamp": {"sec": 5, "nanosec": 7}, "frame_id": "a"}},
    ),
    Case(
        "duration_secs_nsecs",
        "builtin_interfaces/msg/Duration",
        {"secs": 3, "nsecs": 9},
        {"sec": 3, "nanosec": 9},
    ),
    Case(
        "time_secs_nsecs_bare",
        "builtin_interfaces/msg/Time",
        {"secs": 4, "nsecs": 11},
        {"sec": 4, "nanosec": 11},
    ),
    Case(
        "time_now",
        "geometry_msgs/msg/TwistStamped",
        {"header": {"stamp": "now", "frame_id": "a"}},
        {"header": {"stamp": NOW, "frame_id": "a"}},
    ),
    Case(
        "header_stamped_when_left_out",
        "geometry_msgs/msg/TwistStamped",
        {"header": {"frame_id": "b"}},
        {"header": {"stamp": NOW, "frame_id": "b"}},
    ),
    Case(
        "header_left_out_keeps_zero",
        "geometry_msgs/msg/TwistStamped",
        {"twist": {"linear": {"x": 0.5}}},
        {"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""}, "twist": {"linear": {"x": 0.5}}},
    ),
    Case(
        "missing_fields_defaulted",
        "geometry_msgs/msg/Pose",
        {"position": {"x": 1.5}},
        {"position": {"x": 1.5, "y": 0.0, "z": 0.0}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
    ),
    Case(
        "int_for_float",
        "geometry_msgs/msg/Twist",
        {"linear": {"x": 1}, "angular": {"z": -2}},
        {"linear": {"x": 1.0}, "angular": {"z": -2.0}},
    ),
    Case(
        "int_for_float_array",
        "nav_msgs/msg/Odometry",
        {"pose": {"covariance": list(range(36))}},
        {"pose": {"covariance": [float(i) for i in range(36)]}},
    ),
    Case("int_for_octet", "std_msgs/msg/Byte", {"data": 7}, {"data": 7}),
    Case("int_for_char", "std_msgs/msg/Char", {"data": 65}, {"data": 65}),
    Case(
        "uint8_array_base64",
        "std_msgs/msg/UInt8MultiArray",
        {"data": base64.b64encode(bytes([1, 2, 3])).decode()},
        {"data": [1, 2, 3]},
    ),
    Case("uint8_array_list", "std_msgs/msg/UInt8MultiArray", {"data": [1, 2, 3]}, {"data": [1, 2, 3]}),
]
EMBEDDED_CASES = [c for c in CASES if msgtypes.known(c.type)]


def assert_fits(got: Any, want: Any, span: tuple[float, float], path: str = "msg") -> None:
    """``got`` has ``want``'s fields with ``want``'s values; floats must be floats (an int was converted)."""
    if want == NOW:
        stamp = got["sec"] + got["nanosec"] * 1e-9
        assert span[0] - 1 <= stamp <= span[1] + 1, f"{path}: {got} is not the time of the publish {span}"
    elif isinstance(want, dict):
        assert isinstance(got, dict), f"{path}: {got!r}"
        for key, value in want.items():
            assert key in got, f"{path}.{key} missing in {got}"
            assert_fits(got[key], value, span, f"{path}.{key}")
    elif isinstance(want, float):
        assert isinstance(got, float) and got == want, f"{path}: {got!r} != {want!r}"
    else:
        assert got == want, f"{path}: {got!r} != {want!r}"


def plain(msg: Any) -> Any:
    """An rclpy message as plain values: fields by name, arrays and bytes as lists of ints."""
    if hasattr(msg, "get_fields_and_field_types"):
        return {name: plain(getattr(msg, name)) for name in msg.get_fields_and_field_types()}
    if isinstance(msg, (bytes, bytearray)):
        return list(msg) if len(msg) != 1 else msg[0]
    if hasattr(msg, "tolist"):
        return msg.tolist()
    if isinstance(msg, (list, tuple)) or type(msg).__name__ == "array":
        return [plain(v) for v in msg]
    return msg


async def _publish(
    port: int, topic: str, case: Case, until: Callable[[], bool], timeout: float
) -> list[dict]:
    """Advertise and publish ``case.msg`` each 0.1 s until ``until()`` or the server refuses it (an error
    ``status``, rosbridge's answer to a message it cannot convert); the ``status`` frames."""
    statuses: list[dict] = []
    async with aiohttp.ClientSession() as s, s.ws_connect(f"ws://127.0.0.1:{port}/") as ws:
        await ws.send_str(json.dumps({"op": "advertise", "topic": topic, "type": case.type}))
        deadline = time.monotonic() + timeout
        while not until() and not statuses and time.monotonic() < deadline:
            await ws.send_str(json.dumps({"op": "publish", "topic": topic, "msg": case.msg}))
            try:
                frame = await ws.receive(timeout=0.1)
                if (
                    frame.type == aiohttp.WSMsgType.TEXT
                    and (reply := json.loads(frame.data)).get("op") == "status"
                ):
                    statuses.append(reply)
            except asyncio.TimeoutError:
                pass
    return statuses


# -- embedded ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def embedded():
    backend = start_backend("--no-sim")
    yield backend
    backend.stop()


async def _embedded_round(port: int, case: Case) -> tuple[list[dict], list[dict], tuple[float, float]]:
    topic = f"/arbiter_alias/{case.name}"
    got: list[dict] = []
    async with aiohttp.ClientSession() as s, s.ws_connect(f"ws://127.0.0.1:{port}/") as sub:
        await sub.send_str(json.dumps({"op": "subscribe", "topic": topic, "type": case.type}))

        async def read() -> None:
            async for frame in sub:
                reply = json.loads(frame.data)
                if reply.get("op") == "publish":
                    got.append(reply["msg"])

        reader = asyncio.create_task(read())
        start = time.time()
        statuses = await _publish(port, topic, case, lambda: bool(got), 5)
        end = time.time()
        reader.cancel()
    return got, statuses, (start, end)


@pytest.mark.parametrize("case", EMBEDDED_CASES, ids=lambda c: c.name)
def test_embedded_accepts_as_rosbridge(embedded, case):
    got, statuses, span = asyncio.run(_embedded_round(embedded.bridge_port, case))
    assert got, f"nothing arrived; the server said {statuses[:1]}"
    assert_fits(got[0], case.want, span)


# -- --transport ros ---------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def ros_side():
    from ..support import ros as rosmod

    domain = rosmod.use_test_domain()
    next(domain)
    peer = rosmod.Peer("arbiter_alias_peer")
    backend = None
    try:
        backend = start_backend("--transport", "ros", "--no-sim", timeout=30)
        yield peer, backend
    finally:
        if backend is not None:
            backend.stop()
        peer.close()
        next(domain, None)


def _message_class(type_name: str) -> Any:
    import importlib

    pkg, _, name = type_name.split("/")
    return getattr(importlib.import_module(f"{pkg}.msg"), name)


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_ros_accepts_as_rosbridge(ros_side, case):
    peer, backend = ros_side
    topic = f"/arbiter_alias/{case.name}"
    got = peer.collect(_message_class(case.type), topic, plain)
    start = time.time()
    statuses = asyncio.run(_publish(backend.bridge_port, topic, case, lambda: bool(got), 10))
    end = time.time()
    assert wait_for(lambda: bool(got), 1), f"nothing reached rclpy; the server said {statuses[:1]}"
    assert_fits(got[0], case.want, (start, end))
