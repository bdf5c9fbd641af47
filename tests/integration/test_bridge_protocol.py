"""The rosbridge endpoint frame by frame: a real server on 127.0.0.1 and a raw WebSocket client."""

import asyncio
import json
import time

import aiohttp
import pytest

from arbiter_backend.bridge import Client
from arbiter_core import envelope

from ..support.waits import async_until


async def ws_connect(session, backend):
    return await session.ws_connect(f"ws://127.0.0.1:{backend.bridge_port}/")


async def next_frame(ws, op=None, timeout=2.0):
    deadline = time.monotonic() + timeout
    while True:
        msg = await ws.receive(timeout=max(0.01, deadline - time.monotonic()))
        assert msg.type == aiohttp.WSMsgType.TEXT, msg
        frame = json.loads(msg.data)
        if op is None or frame["op"] == op:
            return frame


async def no_frame(ws, wait=0.3):
    with pytest.raises(asyncio.TimeoutError):
        await ws.receive(timeout=wait)


BAD_FRAMES = [
    ("{oops", None, "invalid JSON"),
    ("[1,2,3]", None, "JSON object"),
    ('{"id": "a1"}', "a1", "'op'"),
    ('{"op": 7, "id": "a2"}', "a2", "'op'"),
    ('{"op": "teleport", "id": "a3"}', "a3", "unknown operation"),
    ('{"op": "publish", "id": "a4"}', "a4", "missing field 'topic'"),
    ('{"op": "publish", "id": "a5", "topic": 5, "msg": {}}', "a5", "wrong type"),
    (
        '{"op": "publish", "id": "a6", "topic": "/stamped_cmd_vel", "msg": {"data": 5}}',
        "a6",
        "must be a string",
    ),
    (
        '{"op": "publish", "id": "a7", "topic": "/stamped_cmd_vel", "msg": {"nope": "x"}}',
        "a7",
        "unknown field",
    ),
    ('{"op": "publish", "id": "a8", "topic": "/odom", "msg": 3}', "a8", "must be an object"),
    ('{"op": "publish", "id": "a9", "topic": "/never/seen", "msg": {}}', "a9", "cannot infer"),
    ('{"op": "advertise", "id": "b1", "topic": "/odom", "type": "std_msgs/String"}', "b1", "has type"),
    ('{"op": "advertise", "id": "b2", "topic": "/x", "type": "not a type"}', "b2", "invalid message type"),
    ('{"op": "subscribe", "id": "b3", "topic": "/unknown/topic"}', "b3", "type unknown"),
    ('{"op": "subscribe", "id": "b4", "topic": "/odom", "throttle_rate": "fast"}', "b4", "wrong type"),
    ('{"op": "subscribe", "id": "b5", "topic": "/odom", "queue_length": -3}', "b5", "queue_length must be"),
    (
        '{"op": "subscribe", "id": "c1", "topic": "/odom", "throttle_rate": 99999999999}',
        "c1",
        "throttle_rate",
    ),
    (
        '{"op": "subscribe", "id": "c2", "topic": "/odom bar", "type": "nav_msgs/Odometry"}',
        "c2",
        "invalid topic",
    ),
    ('{"op": "advertise", "id": "c3", "topic": "/a//b", "type": "std_msgs/String"}', "c3", "invalid topic"),
    ('{"op": "advertise", "id": "c4", "topic": "/1st", "type": "std_msgs/String"}', "c4", "invalid topic"),
    ('{"op": "publish", "id": "c5", "topic": "/odom/", "msg": {}}', "c5", "invalid topic"),
    (
        '{"op": "subscribe", "id": "c6", "topic": "/\u00f8dom", "type": "std_msgs/String"}',
        "c6",
        "invalid topic",
    ),
    (
        '{"op": "publish", "id": "b6", "topic": "/cmd_vel_measured", "msg": {"linear": {"x": NaN}}}',
        None,
        "non-finite",
    ),
    ('{"op": "set_level", "id": "b7", "level": "loud"}', "b7", "level must be"),
    (
        '{"op": "publish", "id": "b8", "topic": "/cmd_vel_measured", "msg": {"linear": {"x": null}}}',
        "b8",
        "number",
    ),
]


async def test_every_bad_frame_gets_a_status_and_the_connection_stays_up(server, session):
    ws = await ws_connect(session, server)
    for text, req_id, words in BAD_FRAMES:
        await ws.send_str(text)
        frame = await next_frame(ws)
        assert frame["op"] == "status" and frame["level"] == "error", text
        assert words in frame["msg"], (text, frame)
        assert frame.get("id") == req_id, text
    # oversize frame (2 MiB, above our 1 MiB protocol limit): answered, not a disconnect
    await ws.send_str('{"op": "publish", "topic": "/x", "msg": {"data": "' + "y" * (2 * 1024 * 1024) + '"}}')
    frame = await next_frame(ws)
    assert "exceeds" in frame["msg"]
    await ws.send_bytes(b"\xff\xfe\x00")
    assert "UTF-8" in (await next_frame(ws))["msg"]
    # and valid traffic still works on the same socket
    await ws.send_str(
        json.dumps({"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": envelope.build(0.2, 0)}})
    )
    assert await async_until(lambda: server.tracker.total_seen == 1)
    assert server.endpoint.errors == len(BAD_FRAMES) + 2
    assert not ws.closed
    await ws.close()


async def test_both_type_spellings_and_subscribe_unsubscribe(server, session):
    a = await ws_connect(session, server)
    b = await ws_connect(session, server)
    await a.send_str('{"op": "advertise", "topic": "/chat", "type": "std_msgs/String"}')
    await b.send_str('{"op": "subscribe", "id": "s1", "topic": "/chat", "type": "std_msgs/msg/String"}')
    assert await async_until(lambda: server.bus.subscriber_count("/chat") == 1)
    await a.send_str('{"op": "publish", "topic": "/chat", "msg": {"data": "hi"}}')
    frame = await next_frame(b)
    assert frame == {"op": "publish", "topic": "/chat", "msg": {"data": "hi"}}
    await b.send_str('{"op": "unsubscribe", "id": "s1", "topic": "/chat"}')
    assert await async_until(lambda: server.bus.subscriber_count("/chat") == 0)
    await a.send_str('{"op": "publish", "topic": "/chat", "msg": {"data": "again"}}')
    await no_frame(b)
    # a message with missing fields gets the type's defaults, as rosbridge fills them
    measured = server.bus.subscriber_count("/cmd_vel_measured")
    await b.send_str('{"op": "subscribe", "topic": "/cmd_vel_measured"}')
    assert await async_until(lambda: server.bus.subscriber_count("/cmd_vel_measured") == measured + 1)
    await a.send_str('{"op": "publish", "topic": "/cmd_vel_measured", "msg": {"linear": {"x": 1}}}')
    frame = await next_frame(b)
    assert frame["msg"] == {
        "linear": {"x": 1.0, "y": 0.0, "z": 0.0},
        "angular": {"x": 0.0, "y": 0.0, "z": 0.0},
    }


@pytest.mark.parametrize(("queue_length", "expected"), [(0, ["m0"]), (1, ["m0", "m9"])])
async def test_throttle_rate_and_queue_length(server, session, queue_length, expected):
    pub = await ws_connect(session, server)
    sub = await ws_connect(session, server)
    await pub.send_str('{"op": "advertise", "topic": "/t", "type": "std_msgs/String"}')
    await sub.send_str(
        json.dumps(
            {
                "op": "subscribe",
                "topic": "/t",
                "type": "std_msgs/String",
                "throttle_rate": 600,
                "queue_length": queue_length,
            }
        )
    )
    assert await async_until(lambda: server.bus.subscriber_count("/t") == 1)
    for i in range(10):  # 10 messages at 20 Hz, all inside one 600 ms window after the first
        await pub.send_str(json.dumps({"op": "publish", "topic": "/t", "msg": {"data": f"m{i}"}}))
        await asyncio.sleep(0.05)
    got = []
    with pytest.raises(asyncio.TimeoutError):
        while True:
            got.append((await next_frame(sub, timeout=1.0))["msg"]["data"])
    assert got == expected


async def test_call_service_rosapi_and_unknown_service(server, session):
    ws = await ws_connect(session, server)
    await ws.send_str(
        '{"op": "call_service", "id": "c1", "service": "/rosapi/topic_type", "args": {"topic": "/odom"}}'
    )
    frame = await next_frame(ws)
    assert frame == {
        "op": "service_response",
        "service": "/rosapi/topic_type",
        "id": "c1",
        "result": True,
        "values": {"type": "nav_msgs/msg/Odometry"},
    }
    await ws.send_str(
        '{"op": "call_service", "id": "c2", "service": "/rosapi/topics_for_type", '
        '"args": {"type": "std_msgs/String"}}'
    )
    assert (await next_frame(ws))["values"]["topics"] == ["/latency_report", "/stamped_cmd_vel"]
    await ws.send_str('{"op": "call_service", "id": "c3", "service": "/nope"}')
    frame = await next_frame(ws)
    assert frame["result"] is False and frame["values"] == "Service /nope does not exist"

    def broken(args):  # as a rosapi handler whose graph changed under it (a node that left mid-call)
        raise RuntimeError("the graph changed")

    server.endpoint.services["/rosapi/nodes"] = broken
    await ws.send_str('{"op": "call_service", "id": "c4", "service": "/rosapi/nodes"}')
    frame = await next_frame(ws)  # a response, never a client left waiting
    assert frame["op"] == "service_response" and frame["id"] == "c4" and frame["result"] is False
    assert frame["values"] == "/rosapi/nodes: RuntimeError: the graph changed"


async def test_client_state_is_cleaned_up_on_disconnect(server, session):
    before = server.bus.subscriber_count("/odom")
    clients = [await ws_connect(session, server) for _ in range(20)]
    for ws in clients:
        await ws.send_str('{"op": "subscribe", "topic": "/odom"}')
        await ws.send_str('{"op": "subscribe", "id": "second", "topic": "/odom"}')  # merged, not doubled
    assert await async_until(lambda: server.bus.subscriber_count("/odom") == before + 20)
    assert len(server.endpoint.clients) == 20
    for ws in clients:
        await ws.close()
    assert await async_until(lambda: server.bus.subscriber_count("/odom") == before)
    assert await async_until(lambda: server.endpoint.clients == set())


async def test_a_slow_client_loses_oldest_frames_counted_and_never_blocks():
    class NeverSends:
        pass

    c = Client(NeverSends(), queue_size=3)  # the writer task is never started: a client that reads nothing
    for i in range(10):
        c.send(f"f{i}")
    assert list(c.out) == ["f7", "f8", "f9"]
    assert c.dropped == 7


async def test_many_clients_receive_while_one_does_not_read(server, session):
    silent = await ws_connect(session, server)
    await silent.send_str('{"op": "subscribe", "topic": "/latency_report"}')
    readers = [await ws_connect(session, server) for _ in range(5)]
    for ws in readers:
        await ws.send_str('{"op": "subscribe", "topic": "/latency_report"}')
    pub = await ws_connect(session, server)
    assert await async_until(lambda: server.bus.subscriber_count("/latency_report") >= 6)
    n = 200
    for i in range(n):
        await pub.send_str(
            json.dumps(
                {
                    "op": "publish",
                    "topic": "/stamped_cmd_vel",
                    "msg": {"data": envelope.build(0.1, 0.0, seq=i)},
                }
            )
        )
    for ws in readers:
        seqs = [json.loads((await next_frame(ws))["msg"]["data"])["seq"] for _ in range(n)]
        assert seqs == list(range(n))
    assert server.tracker.total_seen == n
