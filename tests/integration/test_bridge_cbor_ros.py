"""CBOR encodings in ROS mode: from the ROS message itself (byte strings, typed arrays), cbor-raw's CDR,
uint8[] as base64 in JSON, and the per-topic queues through the DDS relay (issue 34, items 3 and 4)."""

import asyncio
import base64
import json
import struct

import aiohttp
import cbor2
import pytest

from ..support.backend import start_backend
from ..support.ros import Odometry, Peer, use_test_domain
from ..support.waits import async_until

Image = pytest.importorskip("sensor_msgs.msg").Image
serialization = pytest.importorskip("rclpy.serialization")

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)


@pytest.fixture
def peer():
    p = Peer("arbiter_cbor_peer")
    yield p
    p.close()


@pytest.fixture
def ros_backend(peer):
    b = start_backend("--transport", "ros", "--no-sim", timeout=30)
    yield b
    b.stop()


def image(seq: int) -> Image:
    m = Image(height=4, width=4, encoding="rgb8", step=12)
    m.header.frame_id = f"f{seq}"
    m.data = bytes((seq + i) % 256 for i in range(48))
    return m


async def test_json_cbor_and_cbor_raw_of_ros_messages(peer, ros_backend):
    cam = peer.node.create_publisher(Image, "/cam", 10)
    odom = peer.node.create_publisher(Odometry, "/odom_in", 10)
    url = f"ws://127.0.0.1:{ros_backend.bridge_port}/"
    async with aiohttp.ClientSession() as session:
        j, c, r = [await session.ws_connect(url) for _ in range(3)]
        await j.send_str('{"op": "subscribe", "topic": "/cam", "type": "sensor_msgs/Image"}')
        await c.send_str(
            '{"op": "subscribe", "topic": "/cam", "type": "sensor_msgs/Image", "compression": "cbor"}'
        )
        await c.send_str(
            '{"op": "subscribe", "topic": "/odom_in", "type": "nav_msgs/Odometry", "compression": "cbor"}'
        )
        await r.send_str(
            '{"op": "subscribe", "topic": "/cam", "type": "sensor_msgs/Image", "compression": "cbor-raw"}'
        )
        assert await async_until(
            lambda: cam.get_subscription_count() > 0 and odom.get_subscription_count() > 0, 15
        )
        # publish until each has one (discovery: the relay may match a moment after the count shows)
        got: dict[str, object] = {}

        async def read(ws, name):
            msg = await ws.receive()
            got[name] = msg

        seq = 0
        tasks = [asyncio.create_task(read(ws, n)) for ws, n in ((j, "json"), (c, "cbor"), (r, "raw"))]
        while not all(t.done() for t in tasks) and seq < 100:
            cam.publish(image(7))
            seq += 1
            await asyncio.wait(tasks, timeout=0.1)
        assert all(t.done() for t in tasks), got
        text = json.loads(got["json"].data)
        assert got["json"].type == aiohttp.WSMsgType.TEXT
        assert base64.b64decode(text["msg"]["data"]) == image(7).data.tobytes()  # uint8[]: base64 in JSON
        frame = cbor2.loads(got["cbor"].data)
        assert got["cbor"].type == aiohttp.WSMsgType.BINARY
        assert frame["op"] == "publish" and frame["topic"] == "/cam"
        assert frame["msg"]["data"] == image(7).data.tobytes()  # uint8[]: a byte string in CBOR
        assert frame["msg"]["height"] == 4 and frame["msg"]["header"]["frame_id"] == "f7"
        raw = cbor2.loads(got["raw"].data)["msg"]
        assert set(raw) == {"secs", "nsecs", "bytes"} and raw["secs"] > 1_700_000_000
        back = serialization.deserialize_message(raw["bytes"], Image)
        assert back.header.frame_id == "f7" and bytes(back.data) == image(7).data.tobytes()

        o = Odometry()
        o.pose.covariance = [float(i) / 4 for i in range(36)]
        for _ in range(100):
            odom.publish(o)
            try:
                msg = await c.receive(timeout=0.1)
            except asyncio.TimeoutError:
                continue
            frame = cbor2.loads(msg.data)
            if frame["topic"] == "/odom_in":
                break
        cov = frame["msg"]["pose"]["covariance"]  # double[36]: the stock server cannot encode this one
        assert cov.tag == 86 and list(struct.unpack("<36d", cov.value)) == [float(i) / 4 for i in range(36)]
