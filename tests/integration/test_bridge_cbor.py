"""rosbridge's CBOR and PNG encodings through the real protocol (issue 34, item 3): embedded transport
here, ROS mode (typed arrays from ROS messages, cbor-raw's CDR) in test_bridge_cbor_ros.py."""

import base64
import io
import json
import random
import struct

import aiohttp
import cbor2

from ..support.waits import async_until


async def connect(session, server):
    return await session.ws_connect(f"ws://127.0.0.1:{server.bridge_port}/")


async def frame_of(ws, timeout=5.0):
    msg = await ws.receive(timeout=timeout)
    if msg.type == aiohttp.WSMsgType.BINARY:
        return "binary", cbor2.loads(msg.data)
    assert msg.type == aiohttp.WSMsgType.TEXT, msg
    return "text", json.loads(msg.data)


ODOM = {
    "header": {"stamp": {"sec": 1, "nanosec": 2}, "frame_id": "odom"},
    "pose": {"pose": {"position": {"x": 1.5}}, "covariance": [float(i) for i in range(36)]},
}


async def test_cbor_subscribers_get_binary_frames_json_ones_text_on_the_same_topic(server, session):
    pub, j, c = [await connect(session, server) for _ in range(3)]
    await j.send_str('{"op": "subscribe", "topic": "/odom", "type": "nav_msgs/Odometry"}')
    await c.send_str('{"op": "subscribe", "topic": "/odom", "compression": "cbor"}')
    await c.send_str(
        '{"op": "subscribe", "topic": "/chat", "type": "std_msgs/String", "compression": "cbor"}'
    )
    assert await async_until(lambda: server.bus.subscriber_count("/chat") == 1)
    await pub.send_str(json.dumps({"op": "publish", "topic": "/odom", "msg": ODOM}))
    await pub.send_str('{"op": "publish", "topic": "/chat", "msg": {"data": "hi"}}')
    kind, frame = await frame_of(j)
    assert kind == "text" and frame["msg"]["pose"]["covariance"] == [float(i) for i in range(36)]
    kind, frame = await frame_of(c)
    assert kind == "binary" and frame["op"] == "publish" and frame["topic"] == "/odom"
    cov = frame["msg"]["pose"]["covariance"]  # a float64 little-endian typed array (RFC 8746 tag 86)
    assert isinstance(cov, cbor2.CBORTag) and cov.tag == 86
    assert list(struct.unpack("<36d", cov.value)) == [float(i) for i in range(36)]
    assert frame["msg"]["pose"]["pose"]["position"]["x"] == 1.5
    kind, frame = await frame_of(c)
    assert (kind, frame) == ("binary", {"op": "publish", "topic": "/chat", "msg": {"data": "hi"}})


async def test_requests_may_come_as_cbor_maps(server, session):
    pub, sub = await connect(session, server), await connect(session, server)
    await sub.send_str('{"op": "subscribe", "topic": "/raw", "type": "std_msgs/String"}')
    assert await async_until(lambda: server.bus.subscriber_count("/raw") == 1)
    await pub.send_bytes(cbor2.dumps({"op": "advertise", "topic": "/raw", "type": "std_msgs/String"}))
    await pub.send_bytes(cbor2.dumps({"op": "publish", "topic": "/raw", "msg": {"data": "from cbor"}}))
    assert (await frame_of(sub))[1]["msg"] == {"data": "from cbor"}
    # byte strings become base64 (uint8[] in rosbridge JSON), typed arrays lists
    await pub.send_bytes(
        cbor2.dumps(
            {
                "op": "publish",
                "topic": "/blob",
                "type": "x",
                "msg": {"data": b"\x00\x01\xff", "v": cbor2.CBORTag(85, struct.pack("<2f", 1.0, 2.5))},
            }
        )
    )
    # /blob has no type: the status error proves the frame was decoded and dispatched
    _, frame = await frame_of(pub)
    assert frame["op"] == "status" and "cannot infer" in frame["msg"]
    await pub.send_bytes(cbor2.dumps({"op": "advertise", "topic": "/blob", "type": "my_msgs/Blob"}))
    await sub.send_str('{"op": "subscribe", "topic": "/blob"}')
    assert await async_until(lambda: server.bus.subscriber_count("/blob") == 1)
    await pub.send_bytes(
        cbor2.dumps(
            {
                "op": "publish",
                "topic": "/blob",
                "msg": {"data": b"\x00\x01\xff", "v": cbor2.CBORTag(85, struct.pack("<2f", 1.0, 2.5))},
            }
        )
    )
    msg = (await frame_of(sub))[1]["msg"]
    assert base64.b64decode(msg["data"]) == b"\x00\x01\xff" and msg["v"] == [1.0, 2.5]


def png_text(frame):
    """What roslibjs's decompressPng does: the image's RGB bytes are the JSON text (read with Pillow,
    an implementation that is not ours)."""
    from PIL import Image

    assert frame["op"] == "png" and set(frame) == {"op", "data"}, frame
    image = Image.open(io.BytesIO(base64.b64decode(frame["data"])))
    assert image.mode == "RGB"
    return json.loads(image.tobytes().decode("utf-8"))  # the '\n' padding is JSON whitespace


async def test_png_subscribers_get_the_json_text_as_an_image_others_plain_text(server, session):
    png, plain = await connect(session, server), await connect(session, server)
    await png.send_str(
        '{"op": "subscribe", "topic": "/chat", "type": "std_msgs/String", "compression": "png"}'
    )
    await plain.send_str('{"op": "subscribe", "topic": "/chat", "type": "std_msgs/String"}')
    await png.send_str(
        '{"op": "subscribe", "topic": "/big", "type": "std_msgs/String", "compression": "png", '
        '"fragment_size": 1000}'
    )
    pub = await connect(session, server)
    await pub.send_str('{"op": "advertise", "topic": "/chat", "type": "std_msgs/String"}')
    await pub.send_str('{"op": "advertise", "topic": "/big", "type": "std_msgs/String"}')
    for ws in (png, plain, pub):
        await settled(ws)
    text = "héllo, png " * 3
    await pub.send_str(json.dumps({"op": "publish", "topic": "/chat", "msg": {"data": text}}))
    kind, frame = await frame_of(png)
    assert kind == "text" and png_text(frame) == {"op": "publish", "topic": "/chat", "msg": {"data": text}}
    assert (await frame_of(plain))[1]["msg"] == {"data": text}
    # a message bigger than fragment_size: fragments of the png frame's text, joined, are the png frame
    big = base64.b64encode(random.Random(7).randbytes(15_000)).decode()  # deflates badly: many fragments
    await pub.send_str(json.dumps({"op": "publish", "topic": "/big", "msg": {"data": big}}))
    parts = []
    while not parts or len(parts) < parts[0]["total"]:
        kind, frag = await frame_of(png)
        assert kind == "text" and frag["op"] == "fragment", frag
        parts.append(frag)
    assert [p["num"] for p in parts] == list(range(len(parts))) and len(parts) > 1
    assert all(len(p["data"]) <= 1000 for p in parts)
    whole = json.loads("".join(p["data"] for p in parts))
    assert png_text(whole)["msg"] == {"data": big}


async def settled(ws):
    """Every frame this client sent before is handled: the server answers a connection's frames in order."""
    await ws.send_str('{"op": "call_service", "id": "sync", "service": "/rosapi/topics"}')
    while (await frame_of(ws))[1].get("id") != "sync":
        pass


BAD = [
    (
        '{"op": "subscribe", "id": "k1", "topic": "/chat", "type": "std_msgs/String", "compression": "gzip"}',
        "k1",
    ),
    ('{"op": "subscribe", "id": "k2", "topic": "/chat", "type": "std_msgs/String", "compression": 3}', "k2"),
    (
        '{"op": "subscribe", "id": "k3", "topic": "/chat", "type": "std_msgs/String", '
        '"compression": "cbor-raw"}',
        "k3",
    ),
    (cbor2.dumps({"op": "publish", "id": "k4", "topic": "/chat", "msg": {"data": float("nan")}}), "k4"),
    (cbor2.dumps({"op": "subscribe", "id": "k5", "topic": "/chat", "compression": "zip"}), "k5"),
    (cbor2.dumps({"op": "teleport", "id": "k6"}), "k6"),
    (cbor2.dumps({"op": "publish", "msg": {"when": cbor2.CBORTag(1, 5)}}), None),
    (cbor2.dumps({1: 2}), None),
    (b"\xa2\x62op", None),  # truncated
    (b"\xa0garbage", None),  # more after the map
]
WORDS = [
    "compression must be",
    "wrong type",
    "cbor-raw needs",
    "non-finite",
    "compression must be",
    "unknown operation",
    "no rosbridge JSON form",
    "keys must be text",
    "invalid CBOR",
    "7 bytes after the first item",
]


async def test_bad_encodings_get_a_status_naming_the_id_and_the_connection_stays(server, session):
    ws = await connect(session, server)
    for (data, req_id), words in zip(BAD, WORDS, strict=True):
        await (ws.send_bytes(data) if isinstance(data, bytes) else ws.send_str(data))
        kind, frame = await frame_of(ws)
        assert kind == "text" and frame["op"] == "status" and frame["level"] == "error", data
        assert words in frame["msg"], (data, frame)
        assert frame.get("id") == req_id, (data, frame)
    await ws.send_str('{"op": "call_service", "id": "ok", "service": "/nope"}')
    assert (await frame_of(ws))[1]["id"] == "ok" and not ws.closed
