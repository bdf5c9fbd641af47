"""A WebSocket client on a plain socket that reads at most ``rate`` bytes a second (a slow link or a
slow client), for the endpoint's pacing tests. It sends frames; it does not parse what it reads."""

from __future__ import annotations

import base64
import json
import os
import socket
import struct
import threading
import time


class SlowReader(threading.Thread):
    def __init__(self, port: int, rate: float, rcvbuf: int = 64 * 1024) -> None:
        super().__init__(daemon=True)
        self.rate = rate
        self.read = 0
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

    def close(self) -> None:
        self.stopped = True
        self.join(timeout=2)
        self.sock.close()
