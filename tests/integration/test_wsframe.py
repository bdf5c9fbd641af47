"""The command path's own WebSocket frames, checked against an independent decoder and aiohttp."""

import struct

import pytest

from arbiter_tui.link.wsframe import mask_bytes, text_frame

from ..support.servers import serve


def decode(frame: bytes) -> tuple[int, bytes]:
    b0, b1 = frame[0], frame[1]
    assert b1 & 0x80, "client frames must be masked"
    n, i = b1 & 0x7F, 2
    if n == 126:
        (n,) = struct.unpack("!H", frame[2:4])
        i = 4
    elif n == 127:
        (n,) = struct.unpack("!Q", frame[2:10])
        i = 10
    mask, body = frame[i : i + 4], frame[i + 4 :]
    assert len(body) == n
    return b0, bytes(c ^ mask[j % 4] for j, c in enumerate(body))


@pytest.mark.parametrize("n", [0, 1, 3, 125, 126, 127, 65535, 65536, 70001])
def test_frames_of_every_length_class_decode(n):
    payload = bytes((i * 7) % 256 for i in range(n))
    b0, got = decode(text_frame(payload, mask=b"\x01\x80\xfe\x33"))
    assert b0 == 0x81 and got == payload


def test_mask_is_an_involution_and_random_by_default():
    p = b'{"op":"publish"}'
    assert mask_bytes(mask_bytes(p, b"abcd"), b"abcd") == p
    assert text_frame(p)[2:6] != text_frame(p)[2:6] or text_frame(p)[2:6] != text_frame(p)[2:6]
    with pytest.raises(ValueError):
        text_frame(p, mask=b"abc")


async def test_aiohttp_server_reads_our_frames():
    import asyncio

    from aiohttp import web

    got = []

    async def handler(request):
        ws = web.WebSocketResponse()
        await ws.prepare(request)
        async for msg in ws:
            got.append(msg.data)
        return ws

    app = web.Application()
    app.router.add_get("/", handler)
    runner, port = await serve(app)
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    writer.write(
        b"GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    await reader.readuntil(b"\r\n\r\n")
    texts = ["hello", "ü" * 100, "x" * 70000]
    for t in texts:
        writer.write(text_frame(t.encode()))
    await writer.drain()
    for _ in range(100):
        if len(got) == len(texts):
            break
        await asyncio.sleep(0.02)
    writer.close()
    await runner.cleanup()
    assert got == texts
