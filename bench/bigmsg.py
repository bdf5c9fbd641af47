#!/usr/bin/env python
"""Big messages beside small ones through the rosbridge endpoint: does a camera starve a small topic?

A publisher (ROS mode: an rclpy node in its own process; embedded: a WebSocket client publishing
JSON) sends a WxH rgb8 ``sensor_msgs/Image`` at 30 Hz and a small ``std_msgs/String`` at 20 Hz holding
its publish time (ns). One WebSocket client subscribes to both, in JSON or ``compression: "cbor"``,
and reads continuously for ``--seconds`` (after a warm-up). Printed per row: image frames/s delivered,
the small topic's latency (receive minus publish time, same host clock) p50/p95/max, the server's CPU
(user+system of the backend process over the window, % of one core), and what the server dropped.

``json-frag`` rows ask for ``fragment_size`` 64 KiB on the camera (rosbridge ``fragment`` frames,
between which the small topic's messages go). The slow client reads its socket at most ``--slow``
image frames' worth of bytes a second (a link or
a client that cannot take the camera's rate; its receive buffer is ``SLOW_RCVBUF``), and asks for
``queue_length: 1`` on the camera, as a viewer of the latest frame would. Every row runs ``--repeat``
times; the table shows medians.

``--stock CMD`` adds rows for the stock rosbridge_server, side by side, with the same rclpy publisher:
CMD starts it with ``{port}`` where its port goes (it must be installed, with its ``rosbridge_msgs``),
for example::

    python bench/bigmsg.py --transport both --seconds 15 --repeat 3 \
        --stock 'ros2 run rosbridge_server rosbridge_websocket --ros-args -p port:={port}'

Its server CPU is that of the process CMD starts; it reports no drops.

``--floor`` adds a ``dds`` row per size: no server and no WebSocket client, but an rclpy node in its
own process subscribing to both topics as the ROS relay does (deserialised messages, default QoS)
and noting each small message's latency when its callback runs. It is the floor any server in front
of DDS stands on, on this machine and under this load: the publisher, DDS's transport and rclpy's
executor. Its "server CPU" is that node's. ``--floor-readers 2`` gives that node a second reader of
the camera, as a relay and a topic monitor each with its own reader would be (session 16: the small
topic's p95 then went from 7 to 60-160 ms).

Last line: one JSON object with every row.
"""

from __future__ import annotations

import argparse
import base64
import contextlib
import json
import os
import random
import re
import shlex
import signal
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import cbor2
from _common import emit, pct

from arbiter_core.listening import parse_listening

# the servers and the publisher run from a folder with no package in it: ``python -m`` puts the working
# directory first on sys.path, ahead of PYTHONPATH, so from another checkout it would import that one
NEUTRAL = tempfile.gettempdir()

SMALL = "/bench/small"
IMAGE = "/bench/image"
WARMUP_S = 2.0
SLOW_RCVBUF = 128 * 1024
FRAGMENT = 64 * 1024  # fragment_size of the json-frag rows
FRAGMENT_OP = re.compile(rb'"op":\s*"fragment"')  # ours writes no spaces, the stock server does
TICK = os.sysconf("SC_CLK_TCK")


# -- a WebSocket reader on a plain socket (so that the slow client can pace its reads) ---------------
class Reader(threading.Thread):
    def __init__(
        self, port: int, subscribe: list[dict], rate_bytes: float | None = None, rcvbuf: int = SLOW_RCVBUF
    ) -> None:
        super().__init__(daemon=True)
        self.sock = socket.socket()
        if rate_bytes is not None:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.connect(("127.0.0.1", port))
        self.sock.sendall(
            b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            b"Sec-WebSocket-Key: "
            + base64.b64encode(os.urandom(16))
            + b"\r\nSec-WebSocket-Version: 13\r\n\r\n"
        )
        head = b""
        while b"\r\n\r\n" not in head:
            head += self.sock.recv(4096)
        assert b" 101 " in head.split(b"\r\n", 1)[0], head
        self.buf = bytearray(head.split(b"\r\n\r\n", 1)[1])
        self.rate = rate_bytes
        self.images: list[int] = []  # receive times (ns)
        self.small: list[tuple[int, int]] = []  # (publish ns, receive ns)
        self.stop = False
        for frame in subscribe:
            self.send(json.dumps(frame).encode())

    def send(self, payload: bytes, opcode: int = 1) -> None:
        mask = b"\x00\x00\x00\x00"  # a valid key that leaves the payload as it is: no Python XOR of MBs
        n = len(payload)
        head = bytes([0x80 | opcode])
        if n < 126:
            head += bytes([0x80 | n])
        elif n < 65536:
            head += bytes([0x80 | 126]) + struct.pack("!H", n)
        else:
            head += bytes([0x80 | 127]) + struct.pack("!Q", n)
        self.sock.sendall(head + mask + payload)

    def run(self) -> None:
        budget, last = 0.0, time.monotonic()
        self.sock.settimeout(0.5)
        while not self.stop:
            want = 1 << 20
            if self.rate is not None:
                now = time.monotonic()
                budget = min(budget + (now - last) * self.rate, 65536.0)
                last = now
                if budget < 4096:
                    time.sleep((4096 - budget) / self.rate)
                    continue
                want = int(budget)
            try:
                data = self.sock.recv(want)
            except TimeoutError:
                continue
            except OSError:
                return
            if not data:
                return
            if self.rate is not None:
                budget -= len(data)
            self.buf += data
            self._frames()

    def _frames(self) -> None:
        buf = self.buf
        while len(buf) >= 2:
            opcode, n, i = buf[0] & 0x0F, buf[1] & 0x7F, 2
            if n == 126:
                if len(buf) < 4:
                    return
                (n,) = struct.unpack_from("!H", buf, 2)
                i = 4
            elif n == 127:
                if len(buf) < 10:
                    return
                (n,) = struct.unpack_from("!Q", buf, 2)
                i = 10
            if len(buf) < i + n:
                return
            now = time.time_ns()
            if opcode in (1, 2):
                head = bytes(buf[i : i + 80])
                if FRAGMENT_OP.search(head):  # only the camera's: whole at its last fragment
                    frag = json.loads(bytes(buf[i : i + n]))
                    if frag["num"] == frag["total"] - 1:
                        self.images.append(now)
                elif SMALL.encode() in head:
                    payload = bytes(buf[i : i + n])
                    frame = json.loads(payload) if opcode == 1 else cbor2.loads(payload)
                    self.small.append((int(frame["msg"]["data"]), now))
                elif IMAGE.encode() in head:
                    self.images.append(now)
            elif opcode == 9:
                self.send(bytes(buf[i : i + n]), opcode=10)
            elif opcode == 8:
                self.stop = True
            del buf[: i + n]

    def close(self) -> None:
        self.stop = True
        self.join(2)
        self.sock.close()


# -- publishers ------------------------------------------------------------------------------------
def publish_ros(width: int, height: int) -> None:
    import rclpy
    from sensor_msgs.msg import Image
    from std_msgs.msg import String

    rclpy.init()
    node = rclpy.create_node("bigmsg_publisher")
    cam = node.create_publisher(Image, IMAGE, 10)
    small = node.create_publisher(String, SMALL, 10)
    img = Image(height=height, width=width, encoding="rgb8", step=width * 3)
    img.data = bytes(random.Random(1).randbytes(width * height * 3))
    _loop(lambda: cam.publish(img), lambda: small.publish(String(data=str(time.time_ns()))))


def floor_subscriber(readers: int = 1) -> None:
    """The ``dds`` row's process: subscribe to both topics as the relay does; one line per message.
    ``readers`` > 1: that many readers of the camera in this process (the others do nothing)."""
    import rclpy
    from sensor_msgs.msg import Image
    from std_msgs.msg import String

    rclpy.init()
    node = rclpy.create_node("bigmsg_floor")
    out = sys.stdout

    def on_small(m: String) -> None:
        out.write(f"S {m.data} {time.time_ns()}\n")
        out.flush()

    def on_image(_m: Image) -> None:
        out.write(f"I {time.time_ns()}\n")
        out.flush()

    node.create_subscription(Image, IMAGE, on_image, 10)
    node.create_subscription(String, SMALL, on_small, 10)
    for _ in range(readers - 1):
        node.create_subscription(Image, IMAGE, lambda _m: None, 10)
    from rclpy.executors import ExternalShutdownException

    with contextlib.suppress(KeyboardInterrupt, ExternalShutdownException):  # stopped by SIGINT
        rclpy.spin(node)


class FloorReader(threading.Thread):
    """What the ``dds`` row's process saw, in the :class:`Reader`'s terms."""

    def __init__(self, proc: subprocess.Popen) -> None:
        super().__init__(daemon=True)
        self.proc = proc
        self.images: list[int] = []
        self.small: list[tuple[int, int]] = []

    def run(self) -> None:
        for line in self.proc.stdout:
            kind, *nums = line.split()
            if kind == "I":
                self.images.append(int(nums[0]))
            elif kind == "S":
                self.small.append((int(nums[0]), int(nums[1])))

    def close(self) -> None:
        pass


def publish_ws(port: int, width: int, height: int) -> None:
    sock = Reader(port, [])
    for topic, type_name in ((IMAGE, "sensor_msgs/Image"), (SMALL, "std_msgs/String")):
        sock.send(json.dumps({"op": "advertise", "topic": topic, "type": type_name}).encode())
    data = base64.b64encode(random.Random(1).randbytes(width * height * 3)).decode()
    image = json.dumps(
        {
            "op": "publish",
            "topic": IMAGE,
            "msg": {"height": height, "width": width, "encoding": "rgb8", "step": width * 3, "data": data},
        }
    ).encode()
    threading.Thread(target=_drain, args=(sock.sock,), daemon=True).start()
    _loop(
        lambda: sock.send(image),
        lambda: sock.send(
            json.dumps({"op": "publish", "topic": SMALL, "msg": {"data": str(time.time_ns())}}).encode()
        ),
    )


def _drain(sock: socket.socket) -> None:
    while sock.recv(65536):
        pass


def _loop(image, small) -> None:
    t0 = time.monotonic()
    next_image, next_small = t0, t0
    while True:
        now = time.monotonic()
        if now >= next_image:
            image()
            next_image += 1 / 30
        if now >= next_small:
            small()
            next_small += 1 / 20
        time.sleep(max(0.0, min(next_image, next_small) - time.monotonic()))


# -- one row -----------------------------------------------------------------------------------------
def cpu_s(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def foreign_env(env: dict) -> dict:
    """``env`` for a program of another install (the stock server, perhaps in a venv of its own): without
    what this venv's ROS wheels set at start (``ros_wheels_bootstrapper`` puts its libraries on
    LD_LIBRARY_PATH and marks the environment done), so that the other install's own libraries load."""
    out = dict(env)
    out.pop("_ROS_WHEELS_BOOTSTRAP_COMPLETE", None)
    ours = sys.prefix
    parts = [p for p in out.get("LD_LIBRARY_PATH", "").split(os.pathsep) if p and not p.startswith(ours)]
    if parts:
        out["LD_LIBRARY_PATH"] = os.pathsep.join(parts)
    else:
        out.pop("LD_LIBRARY_PATH", None)
    return out


def start_stock(cmd: str, env: dict) -> tuple[subprocess.Popen, int]:
    """The stock rosbridge_server from ``cmd`` on a free port, once that port takes connections."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    # its log (and, stopped, a traceback a spin) would drown the table
    args = shlex.split(cmd.replace("{port}", str(port)))
    quiet = subprocess.DEVNULL
    proc = subprocess.Popen(args, env=foreign_env(env), stdout=quiet, stderr=quiet, cwd=NEUTRAL)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and proc.poll() is None:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return proc, port
        time.sleep(0.1)
    proc.kill()
    raise RuntimeError(f"the stock server did not listen on {port}: {cmd}")


def start_backend(transport: str, env: dict, extra: str = "") -> tuple[subprocess.Popen, int, int]:
    cmd = [sys.executable, "-m", "arbiter_backend.cli", "--transport", transport, "--no-sim"]
    cmd += ["--bridge-port", "0", "--api-port", "0", "--max-frame", "16000000", "--log-level", "WARNING"]
    cmd += shlex.split(extra)
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, env=env, cwd=NEUTRAL)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        found = parse_listening(proc.stdout.readline())
        if found is not None:
            return proc, found.bridge_port, found.api_port
    proc.kill()
    raise RuntimeError("backend did not start")


def run_row(
    transport: str,
    width: int,
    height: int,
    encoding: str,
    seconds: float,
    slow: float | None,
    rcvbuf: int = SLOW_RCVBUF,
    stock: str | None = None,
    backend_args: str = "",
    floor_readers: int = 1,
) -> dict:
    env = {
        **os.environ,
        "ROS_DOMAIN_ID": str(random.randint(1, 100)),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
    }
    here = str(Path(__file__).resolve().parent.parent)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (here, env.get("PYTHONPATH")) if p)
    if transport == "dds":
        floor = [sys.executable, __file__, "--floor-subscriber", str(floor_readers)]
        proc = subprocess.Popen(floor, env=env, cwd=NEUTRAL, stdout=subprocess.PIPE, text=True)
        port, api_port = 0, None
    elif transport == "stock":
        proc, port = start_stock(stock or "", env)
        api_port = None
    else:
        proc, port, api_port = start_backend(transport, env, backend_args)
    me = [
        sys.executable,
        __file__,
        "--publisher",
        "embedded" if transport == "embedded" else "ros",
        "--size",
        f"{width}x{height}",
        "--port",
        str(port),
    ]
    pub = subprocess.Popen(me, env=env, cwd=NEUTRAL)
    try:
        extra = {"compression": "cbor"} if encoding == "cbor" else {}
        cam = {"op": "subscribe", "topic": IMAGE, "type": "sensor_msgs/Image", **extra}
        if slow is not None:
            cam["queue_length"] = 1
        if encoding == "json-frag":
            cam["fragment_size"] = FRAGMENT
        reader: Reader | FloorReader = (
            FloorReader(proc)
            if transport == "dds"
            else Reader(
                port,
                [cam, {"op": "subscribe", "topic": SMALL, "type": "std_msgs/String", **extra}],
                rate_bytes=None
                if slow is None
                else slow * width * height * 3 * (1 if encoding == "cbor" else 4 / 3),
                rcvbuf=rcvbuf,
            )
        )
        reader.start()
        deadline = time.monotonic() + 30
        while not (reader.images and reader.small) and time.monotonic() < deadline:
            time.sleep(0.05)  # discovery, first frames
        time.sleep(WARMUP_S)
        t0, c0 = time.time_ns(), cpu_s(proc.pid)
        time.sleep(seconds)
        t1, c1 = time.time_ns(), cpu_s(proc.pid)
        images = [t for t in reader.images if t0 <= t < t1]
        lat = [(r - p) / 1e6 for p, r in reader.small if t0 <= r < t1]
        sent = int((t1 - t0) / 1e9 * 20)
        try:
            import httpx

            if api_port is None:
                raise LookupError("the stock server and the floor have no /api/health")
            dropped = httpx.get(f"http://127.0.0.1:{api_port}/api/health", timeout=5).json()["bridge"][
                "dropped"
            ]
        except Exception:
            dropped = {}
        reader.close()
        return {
            "transport": transport,
            "size": f"{width}x{height}",
            "encoding": encoding,
            "client": "normal" if slow is None else f"slow ({slow:g}/s, {rcvbuf // 1024}K)",
            "frames_per_s": round(len(images) / ((t1 - t0) / 1e9), 2),
            "small_p50_ms": pct(lat, 0.5),
            "small_p95_ms": pct(lat, 0.95),
            "small_max_ms": round(max(lat), 3) if lat else None,
            "small_received": len(lat),
            "small_expected": sent,
            "server_cpu_pct": round(100 * (c1 - c0) / ((t1 - t0) / 1e9), 1),
            "dropped": dropped,
        }
    finally:
        pub.kill()
        pub.wait()
        # the stock server stops on SIGINT (rclpy's handler), not on SIGTERM; ours on either
        proc.send_signal(signal.SIGINT if transport in ("stock", "dds") else signal.SIGTERM)
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def median_row(rows: list[dict]) -> dict:
    out = dict(rows[0])
    for key in ("frames_per_s", "small_p50_ms", "small_p95_ms", "small_max_ms", "server_cpu_pct"):
        vals = [r[key] for r in rows if r[key] is not None]
        out[key] = round(statistics.median(vals), 3) if vals else None
    out["runs"] = len(rows)
    return out


def _f(value: float | None, width: int, digits: int) -> str:
    """A figure of the table, or '-' where there is none (no small message came in the window)."""
    return f"{'-':>{width}}" if value is None else f"{value:{width}.{digits}f}"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--transport", choices=("embedded", "ros", "both"), default="both")
    p.add_argument(
        "--stock",
        metavar="CMD",
        help="also measure the stock rosbridge_server that CMD starts ('{port}' in CMD: its port)",
    )
    p.add_argument("--sizes", default="640x480,1280x720")
    p.add_argument("--encodings", default="json,cbor")
    p.add_argument("--seconds", type=float, default=15.0)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument(
        "--slow", type=float, default=5.0, help="the slow client's image frames/s (0: no such row)"
    )
    p.add_argument(
        "--slow-rcvbuf",
        type=int,
        default=SLOW_RCVBUF,
        help="the slow client's SO_RCVBUF (Linux doubles it): bytes a small message may wait behind there",
    )
    p.add_argument(
        "--backend-args",
        default="",
        metavar="ARGS",
        help="more arguments for arbiter-backend, e.g. \"--topics-exclude '*'\" (our rows only)",
    )
    p.add_argument(
        "--floor",
        action="store_true",
        help="add a 'dds' row per size: an rclpy node subscribing to both topics, no server (the floor)",
    )
    p.add_argument("--publisher", help=argparse.SUPPRESS)
    p.add_argument(
        "--floor-readers",
        type=int,
        default=1,
        metavar="N",
        help="the 'dds' row's readers of the camera in its one process (2: as a relay beside a monitor)",
    )
    p.add_argument("--floor-subscriber", type=int, help=argparse.SUPPRESS)
    p.add_argument("--size", help=argparse.SUPPRESS)
    p.add_argument("--port", type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.floor_subscriber:
        floor_subscriber(args.floor_subscriber)
        return
    if args.publisher:
        w, h = map(int, args.size.split("x"))
        publish_ros(w, h) if args.publisher == "ros" else publish_ws(args.port, w, h)
        return
    transports = ("embedded", "ros") if args.transport == "both" else (args.transport,)
    if args.stock:
        transports = (*transports, "stock")
    sizes = [tuple(map(int, s.split("x"))) for s in args.sizes.split(",")]
    encodings = args.encodings.split(",")
    cases = [(t, w, h, e, None) for t in transports for (w, h) in sizes for e in encodings]
    if args.floor:
        cases = [("dds", w, h, "-", None) for (w, h) in sizes] + cases
    if args.slow:
        slow_encodings = [*encodings, "json-frag"] if "json" in encodings else encodings
        cases += [(t, *sizes[0], e, args.slow) for t in transports for e in slow_encodings]
    rows = []
    head = f"{'transport':9} {'size':9} {'enc':9} {'client':18} {'frames/s':>8} {'p50 ms':>8} {'p95 ms':>8}"
    print(head + f" {'max ms':>8} {'small':>9} {'cpu %':>6}  dropped", flush=True)
    for t, w, h, e, slow in cases:
        row = median_row(
            [
                run_row(
                    t,
                    w,
                    h,
                    e,
                    args.seconds,
                    slow,
                    args.slow_rcvbuf,
                    args.stock,
                    args.backend_args,
                    args.floor_readers,
                )
                for _ in range(args.repeat)
            ]
        )
        rows.append(row)
        print(
            f"{row['transport']:9} {row['size']:9} {row['encoding']:9} {row['client']:18} "
            f"{_f(row['frames_per_s'], 8, 2)} {_f(row['small_p50_ms'], 8, 2)} "
            f"{_f(row['small_p95_ms'], 8, 2)} {_f(row['small_max_ms'], 8, 2)} "
            f"{row['small_received']:4}/{row['small_expected']:<4} "
            f"{_f(row['server_cpu_pct'], 6, 1)}  {row['dropped']}",
            flush=True,
        )
    if not args.stock:
        print("stock rosbridge_server: not measured (--stock CMD measures it where it is installed)")
    emit({"bench": "bigmsg", "seconds": args.seconds, "repeat": args.repeat, "rows": rows})


if __name__ == "__main__":
    main()
