"""A WebSocket client on a plain socket that reads at most ``rate`` bytes a second (a slow link or a
slow client), for the endpoint's pacing tests. It sends frames; with ``frames`` it also parses the
server's (unmasked, unfragmented) data frames and keeps each one's payload with the time it was read."""

from __future__ import annotations

import base64
import json
import os
import socket
import struct
import threading
import time


class SlowReader(threading.Thread):
    def __init__(self, port: int, rate: float, rcvbuf: int = 64 * 1024, frames: bool = False) -> None:
        super().__init__(daemon=True)
        self.rate = rate
        self.read = 0
        self.parse = frames
        self.frames: list[tuple[float, bytes]] = []  # (time.monotonic() when read whole, payload)
        self._buf = bytearray()
        self.stopped = False
        self.sock = socket.socket()
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.connect(("127.0.0.1", port))
        key = base64.b64encode(os.urandom(16))
        self.sock.sendall(
            b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            b"Sec-WebSocket-Key: " + key + b"\r\nSec-WebSocket-Version: 13\r\n\r\n"
        )
        head = b""
        while b"\r\n\r\n" not in head:
            head += self.sock.recv(1)  # byte by byte: nothing of the frames after it is taken
        assert b" 101 " in head.split(b"\r\n", 1)[0], head

    def send_json(self, obj: object) -> None:
        payload = json.dumps(obj).encode()
        n = len(payload)
        size = bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack("!H", n)
        self.sock.sendall(b"\x81" + size + b"\x00\x00\x00\x00" + payload)  # a zero mask key

    def run(self) -> None:
        start = time.monotonic()
        self.sock.settimeout(0.2)
        while not self.stopped:
            allowed = int((time.monotonic() - start) * self.rate) - self.read
            if allowed < 4096:
                time.sleep((4096 - allowed) / self.rate)
                continue
            try:
                data = self.sock.recv(min(allowed, 65536))
            except TimeoutError:
                continue
            except OSError:
                return
            if not data:
                return
            self.read += len(data)
            if self.parse:
                self._buf += data
                self._frames(time.monotonic())

    def _frames(self, now: float) -> None:
        buf = self._buf
        while len(buf) >= 2:
            n, head = buf[1] & 0x7F, 2
            if n == 126:
                if len(buf) < 4:
                    return
                n, head = struct.unpack("!H", buf[2:4])[0], 4
            elif n == 127:
                if len(buf) < 10:
                    return
                n, head = struct.unpack("!Q", buf[2:10])[0], 10
            if len(buf) < head + n:
                return
            if buf[0] & 0x0F in (1, 2):  # text and binary; not pings
                self.frames.append((now, bytes(buf[head : head + n])))
            del buf[: head + n]

    def close(self) -> None:
        self.stopped = True
        self.join(timeout=2)
        self.sock.close()
