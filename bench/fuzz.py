#!/usr/bin/env python
"""Throw malformed input at a running backend while a valid command stream flows alongside.

Generated, from ``--seed`` (the same seed gives the same cases):

* rosbridge frames: random bytes, random unicode text, truncated JSON, deep nesting,
  huge numbers, wrong field types, bad topic names, unknown ops, 10 MB frames, and
  one frame over the transport limit (the server closes that socket with 1009);
* envelopes: well-formed ``publish`` frames on /stamped_cmd_vel whose ``data`` is a bad
  stamped command (invalid JSON, missing fields, wrong types, non-finite numbers,
  oversize), plus extreme-but-valid ones (1e308 velocities, stamps from 1970 or the future);
* HTTP requests: bad query values, unknown paths, wrong methods, and raw malformed
  requests (garbage, oversize request lines and headers, broken chunking).

Pass criteria, all checked (exit status 1 and the reason when one fails):

* every bad frame is answered with one ``status`` error (or, for the oversize one, the
  socket is closed), and none with "internal error";
* every bad envelope is counted in the tracker's ``rejected`` and none is forwarded;
* every HTTP request gets a 4xx answer (never a 5xx, never silence);
* nothing non-finite or beyond the limits reaches /cmd_vel_measured;
* the valid stream (100 Hz, its own connection) is recorded completely, in order;
* afterwards the backend still answers on both ports.

    python bench/fuzz.py                       # 10,000 cases, seed 1
    python bench/fuzz.py --count 1500 --seed 7 # the tests' deterministic subset

Last line: JSON.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import math
import os
import random
import sys
import tempfile
import time
import urllib.parse
from dataclasses import dataclass, field
from typing import Any

import aiohttp
import httpx
from _common import emit, rss_kb

from arbiter_core import envelope
from arbiter_tui.link.embedded import EmbeddedBackend

MAX_LINEAR, MAX_ANGULAR = 1.0, 2.0  # the backend's default limits
VALID_SEQ0 = 1_000_000_000  # the valid stream's sequence numbers, far from any fuzz case
BATCH = 50
HUGE = 10 * 1024 * 1024
OVER_TRANSPORT = 17 * 1024 * 1024

VALID_FRAMES = [
    {"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": envelope.build(0.1, 0.0, seq=1)}},
    {"op": "subscribe", "topic": "/odom", "type": "nav_msgs/Odometry", "throttle_rate": 100},
    {"op": "advertise", "topic": "/stamped_cmd_vel", "type": "std_msgs/String"},
    {"op": "unsubscribe", "topic": "/odom", "id": "s1"},
    {"op": "call_service", "service": "/rosapi/topics", "id": "c1", "args": {}},
    {"op": "set_level", "level": "error"},
]
WRONG_VALUES: list[Any] = [None, True, 0, -1, 3.5, "", "x", [], [1, 2], {}, {"a": 1}]
REQUIRED = {  # op -> required fields whose wrong type must be an error
    "subscribe": ("topic",),
    "advertise": ("topic", "type"),
    "publish": ("topic",),
    "unsubscribe": ("topic",),
    "call_service": ("service",),
    "set_level": ("level",),
}
BAD_TOPICS = [
    "",
    "/",
    "//odom",
    "/odom/",
    "/1odom",
    "/odom bar",
    "/ødom",
    "/😀",
    "/a\u0000b",
    "/a\u202eb",
    "~/x/../y",
    "/" + "a" * 300,
    "/\ud800",
]


@dataclass
class Case:
    kind: str
    payload: str | bytes
    expect: str  # "status" | "rejected" | "accepted" | "close"


@dataclass
class Report:
    sent: dict[str, int] = field(default_factory=dict)
    failures: list[str] = field(default_factory=list)

    def count(self, kind: str) -> None:
        self.sent[kind] = self.sent.get(kind, 0) + 1

    def fail(self, msg: str) -> None:
        if len(self.failures) < 50:
            self.failures.append(msg[:300])


# -- generators -----------------------------------------------------------------------------------
def rand_text(rng: random.Random, n: int) -> str:
    pools = [
        (0x20, 0x7E),
        (0x00, 0x1F),
        (0xA0, 0x2FF),
        (0x400, 0x4FF),
        (0x4E00, 0x4FFF),
        (0x1F600, 0x1F64F),
        (0x202A, 0x202E),
    ]
    out = []
    for _ in range(n):
        lo, hi = rng.choice(pools)
        out.append(chr(rng.randint(lo, hi)))
    return "".join(out)


def dumps(obj: Any) -> str:
    return json.dumps(obj, ensure_ascii=False, separators=(",", ":"))


def frame_case(rng: random.Random) -> Case:
    kind = rng.choice(
        ["bytes", "text", "truncated", "deep", "huge_number", "wrong_type", "bad_topic", "unknown_op"]
    )
    if kind == "bytes":
        return Case(kind, rng.randbytes(rng.randint(0, 400)), "status")
    if kind == "text":
        text = rand_text(rng, rng.randint(0, 200))
        if text.lstrip().startswith("{"):
            text = "x" + text  # never a chance JSON object
        return Case(kind, text, "status")
    if kind == "truncated":
        text = dumps(rng.choice(VALID_FRAMES))
        return Case(kind, text[: rng.randint(0, len(text) - 1)], "status")
    if kind == "deep":
        n = rng.choice([50, 1000, 5000, 100_000])
        shape = rng.choice(["array", "msg", "args"])
        if shape == "array":
            return Case(kind, "[" * n + "]" * n, "status")
        inner = '{"a":' * n + "1" + "}" * n
        if shape == "msg":
            return Case(kind, '{"op":"publish","topic":"/stamped_cmd_vel","msg":' + inner + "}", "status")
        return Case(
            kind, '{"op":"call_service","service":"/rosapi/topic_type","args":' + inner + "}", "status"
        )
    if kind == "huge_number":
        # infinities, ints past Python's 4300-digit parse limit, ints too big for any range,
        # and tiny floats that parse as 0.0 (a float where an int is required)
        num = rng.choice(["1e400", "-1e400", "9" * 4000, "9" * 5000, "1e-400", "123456789" * 30, "-0.0"])
        field_name = rng.choice(["throttle_rate", "queue_length"])
        return Case(kind, f'{{"op":"subscribe","topic":"/odom","{field_name}":{num}}}', "status")
    if kind == "wrong_type":
        op = rng.choice(list(REQUIRED))
        base = next(dict(f) for f in VALID_FRAMES if f["op"] == op)
        name = rng.choice(REQUIRED[op])
        value = rng.choice([v for v in WRONG_VALUES if not isinstance(v, str)])
        if rng.random() < 0.3:
            base.pop(name, None)  # missing instead of wrong
        else:
            base[name] = value
        if rng.random() < 0.3:
            base["id"] = rng.choice(WRONG_VALUES)
        return Case(kind, dumps(base), "status")
    if kind == "bad_topic":
        op = rng.choice(["subscribe", "advertise", "publish"])
        frame: dict[str, Any] = {"op": op, "topic": rng.choice(BAD_TOPICS), "type": "std_msgs/String"}
        if op == "publish":
            frame["msg"] = {"data": "x"}
        return Case(kind, json.dumps(frame), "status")  # ASCII-escaped: lone surrogates survive
    op = rng.choice(
        ["", "PUBLISH", "fragment", "png", "status", "service_response", rand_text(rng, 12), "x" * 500]
    )
    return Case("unknown_op", dumps({"op": op, "topic": "/odom"}), "status")


def envelope_case(rng: random.Random, seq: int) -> Case:
    stamp = time.time() * 1000.0
    good = {"header": {"stamp": stamp, "seq": seq}, "twist": {"linear": {"x": 0.1}, "angular": {"z": 0.0}}}
    kind = rng.choice(
        ["bad_json", "not_object", "missing", "wrong_type", "non_finite", "too_large", "extreme", "odd_stamp"]
    )
    data: str
    expect = "rejected"
    if kind == "bad_json":
        text = json.dumps(good)
        data = rng.choice([text[: rng.randint(0, len(text) - 1)], rand_text(rng, 30), "{'a': 1}", ""])
    elif kind == "not_object":
        data = rng.choice(["[]", "1", '"x"', "null", "true", "[1,2,3]"])
    elif kind == "missing":
        path = rng.choice(
            [("header",), ("header", "stamp"), ("twist",), ("twist", "linear"), ("twist", "angular", "z")]
        )
        obj = json.loads(json.dumps(good))
        cur = obj
        for key in path[:-1]:
            cur = cur[key]
        del cur[path[-1]]
        data = json.dumps(obj)
    elif kind == "wrong_type":
        obj = json.loads(json.dumps(good))
        where = rng.choice(["stamp", "x", "z", "seq", "header", "twist", "linear"])
        value = rng.choice(
            ['"1"', "true", "null", "[]", "{}"] if where in ("stamp", "x", "z") else ['"s"', "1.5", "[]"]
        )
        target = {
            "stamp": ("header", "stamp"),
            "x": ("twist", "linear", "x"),
            "z": ("twist", "angular", "z"),
            "seq": ("header", "seq"),
            "header": ("header",),
            "twist": ("twist",),
            "linear": ("twist", "linear"),
        }[where]
        cur = obj
        for key in target[:-1]:
            cur = cur[key]
        cur[target[-1]] = "__V__"
        data = json.dumps(obj).replace('"__V__"', value)
    elif kind == "non_finite":
        token = rng.choice(["NaN", "Infinity", "-Infinity", "1e400", "-1e999"])
        key = rng.choice(['"stamp"', '"x"', '"z"', '"offset_ms"'])
        text = json.dumps(good)
        if key == '"offset_ms"':
            data = text.replace('"seq":', f'"offset_ms":{token},"seq":')
        else:
            head, _, rest = text.partition(key + ":")
            value_end = min(i for i in (rest.find(","), rest.find("}")) if i >= 0)
            data = head + key + ":" + token + rest[value_end:]
    elif kind == "too_large":
        obj = json.loads(json.dumps(good))
        obj["pad"] = "p" * (envelope.MAX_ENVELOPE_BYTES + rng.randint(1, 5000))
        data = json.dumps(obj)
    elif kind == "extreme":  # valid: accepted, recorded, clamped before the robot
        v = rng.choice([1e308, -1e308, 5e-324, 1e6, -7.5])
        w = rng.choice([1e308, -1e308, 0.0, 123.0])
        data = envelope.build(v, w, seq=seq)
        expect = "accepted"
    else:  # valid but a stamp from 1970 or the far future: recorded (stale or negative), never a crash
        obj = json.loads(json.dumps(good))
        obj["header"]["stamp"] = rng.choice([0, 1, stamp + 86_400_000.0 * 365, 1e15])
        data = json.dumps(obj)
        expect = "accepted"
    frame = {"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": data}}
    return Case(f"envelope_{kind}", json.dumps(frame), expect)


def http_case(rng: random.Random) -> tuple[str, Any]:
    kind = rng.choice(["bad_query", "unknown_path", "wrong_method", "raw"])
    if kind == "bad_query":
        name = rng.choice(["limit", "since"])
        value = rng.choice(
            [
                "abc",
                "-1",
                "1e3",
                "99999999999999999999999",
                "",
                "%20",
                "0x10",
                "1.5",
                "%F0%9F%98%80",
                "%00",
                "9" * 5000,
            ]
        )
        if name == "since" and value in ("",):
            value = "-5"
        return kind, ("GET", f"/api/latency?{name}={value}")
    if kind == "unknown_path":
        path = rng.choice(
            [
                "/",
                "/api",
                "/api/",
                "/api/latency/1",
                "/../etc/passwd",
                "/%2e%2e/",
                "/api/healthz",
                "/" + urllib.parse.quote(rand_text(rng, 20)),
                "/" + "a" * 3000,
            ]
        )
        return kind, ("GET", path)
    if kind == "wrong_method":
        return kind, (
            rng.choice(["POST", "PUT", "DELETE", "PATCH"]),
            rng.choice(["/api/latency", "/api/health"]),
        )
    raw = rng.choice(
        [
            rng.randbytes(rng.randint(1, 300)) + b"\r\n\r\n",
            b"GET /api/health HTTP/9.9\r\n\r\n",
            b"GET " + b"/a" * 20000 + b" HTTP/1.1\r\nHost: x\r\n\r\n",
            b"GET /api/health HTTP/1.1\r\nHost: x\r\nX-Big: " + b"b" * 20000 + b"\r\n\r\n",
            b"POST /api/latency HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n"
            b"zz\r\nhello\r\n0\r\n\r\n",
            b"GET /api/health HTTP/1.1\r\nHost: x\r\nBad\x00Header: 1\r\n\r\n",
            b"GET /api/health HTTP/1.1\r\nContent-Length: -5\r\nHost: x\r\n\r\n",
            b"\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03" + rng.randbytes(60) + b"\r\n\r\n",  # TLS hello
        ]
    )
    return "raw", raw


# -- running ----------------------------------------------------------------------------------------
async def collect_answers(
    ws: aiohttp.ClientWebSocketResponse, n: int, timeout: float
) -> tuple[list[dict], bool]:
    """Read up to ``n`` status frames; (frames, closed)."""
    got: list[dict] = []
    deadline = time.monotonic() + timeout
    while len(got) < n:
        left = deadline - time.monotonic()
        if left <= 0:
            break
        try:
            msg = await asyncio.wait_for(ws.receive(), left)
        except TimeoutError:
            break
        if msg.type == aiohttp.WSMsgType.TEXT:
            frame = json.loads(msg.data)
            if frame.get("op") == "status":
                got.append(frame)
            elif frame.get("op") == "service_response":  # a failed call is answered this way
                ok = frame.get("result") is False
                got.append(
                    {"op": "status", "level": "error" if ok else "info", "msg": str(frame.get("values"))}
                )
        elif msg.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.ERROR):
            return got, True
    return got, False


async def fuzz_frames(session: aiohttp.ClientSession, url: str, cases: list[Case], report: Report) -> None:
    ws = await session.ws_connect(url, max_msg_size=0)
    for i in range(0, len(cases), BATCH):
        batch = cases[i : i + BATCH]
        for c in batch:
            report.count(c.kind)
            if isinstance(c.payload, bytes):
                await ws.send_bytes(c.payload)
            else:
                await ws.send_str(c.payload)
        expected = sum(c.expect == "status" for c in batch)
        answers, closed = await collect_answers(ws, expected, timeout=10.0)
        if closed:
            report.fail(f"frames {i}..{i + len(batch)}: the server closed the socket")
            ws = await session.ws_connect(url, max_msg_size=0)
        if len(answers) != expected:
            kinds = sorted({c.kind for c in batch})
            report.fail(
                f"frames {i}..{i + len(batch)} ({', '.join(kinds)}): {len(answers)} answers for {expected}"
            )
        for a in answers:
            if a.get("level") != "error":
                report.fail(f"status of level {a.get('level')}: {a.get('msg')}")
            if "internal error" in str(a.get("msg")):
                report.fail(f"internal error: {a.get('msg')}")
    # after the loop: nothing more is pending
    extra, _ = await collect_answers(ws, 1, timeout=0.5)
    if extra:
        report.fail(f"unexpected extra answers: {extra[:2]}")
    await ws.close()


async def huge_frames(session: aiohttp.ClientSession, url: str, count: int, report: Report) -> None:
    ws = await session.ws_connect(url, max_msg_size=0)
    big = '{"op":"publish","topic":"/stamped_cmd_vel","msg":{"data":"' + "A" * HUGE + '"}}'
    for _ in range(count):
        report.count("frame_10MB")
        await ws.send_str(big)
        answers, closed = await collect_answers(ws, 1, timeout=20.0)
        if closed or len(answers) != 1 or "exceeds" not in answers[0].get("msg", ""):
            report.fail(f"10 MB frame: {answers} closed={closed}")
    await ws.close()
    ws = await session.ws_connect(url, max_msg_size=0)
    report.count("frame_over_transport_limit")
    with contextlib.suppress(ConnectionError):  # the server may close while the frame is still going out
        await ws.send_str("[" + " " * OVER_TRANSPORT + "]")
    _, closed = await collect_answers(ws, 1, timeout=20.0)
    if not closed or ws.close_code not in (1009, 1006):  # 1006: closed while the frame was still going out
        report.fail(f"a 17 MB frame: closed={closed} code={ws.close_code} (1009 or 1006 expected)")
    await ws.close()


async def fuzz_http(api: str, cases: list[tuple[str, Any]], report: Report) -> None:
    host, port = api.removeprefix("http://").split(":")
    async with httpx.AsyncClient(base_url=api, timeout=5.0) as http:
        for kind, spec in cases:
            report.count(f"http_{kind}")
            if kind != "raw":
                method, path = spec
                try:
                    r = await http.request(method, path)
                except httpx.HTTPError as exc:
                    report.fail(f"{method} {path[:80]}: {type(exc).__name__}")
                    continue
                if not 400 <= r.status_code < 500:
                    report.fail(f"{method} {path[:80]}: HTTP {r.status_code}")
                elif r.headers.get("content-type", "").startswith("application/json"):
                    body = r.json()
                    if body.get("status") != r.status_code or not body.get("error"):
                        report.fail(f"{method} {path[:80]}: body {body}")
                continue
            reader, writer = await asyncio.open_connection(host, int(port))
            try:
                writer.write(spec)
                await writer.drain()
                line = await asyncio.wait_for(reader.readline(), 5.0)
            except (TimeoutError, ConnectionError) as exc:
                report.fail(f"raw {spec[:40]!r}: {type(exc).__name__}")
                continue
            finally:
                writer.close()
            parts = line.split()
            if len(parts) < 2 or not parts[0].startswith(b"HTTP/1.") or not 400 <= int(parts[1]) < 500:
                report.fail(f"raw {spec[:40]!r}: answered {line[:60]!r}")


async def valid_stream(
    session: aiohttp.ClientSession, url: str, stop: asyncio.Event, sent: list[int]
) -> float:
    """Stamped commands at 100 Hz until ``stop``; returns the worst lag behind schedule (s)."""
    ws = await session.ws_connect(url)
    await ws.send_str(json.dumps({"op": "advertise", "topic": "/stamped_cmd_vel", "type": "std_msgs/String"}))
    await asyncio.sleep(0.1)
    period = 0.01
    next_t = time.monotonic()
    seq = VALID_SEQ0
    worst = 0.0
    while not stop.is_set():
        worst = max(worst, time.monotonic() - next_t)
        data = envelope.build(0.1, 0.0, seq=seq)
        await ws.send_str(json.dumps({"op": "publish", "topic": "/stamped_cmd_vel", "msg": {"data": data}}))
        sent.append(seq)
        seq += 1
        next_t += period
        await asyncio.sleep(max(0.0, next_t - time.monotonic()))
    await ws.close()
    return worst


async def watch_robot(
    session: aiohttp.ClientSession, url: str, seen: list[tuple[float, float]], report: Report
) -> None:
    ws = await session.ws_connect(url)
    await ws.send_str(
        json.dumps({"op": "subscribe", "topic": "/cmd_vel_measured", "type": "geometry_msgs/Twist"})
    )
    async for msg in ws:
        if msg.type != aiohttp.WSMsgType.TEXT:
            break
        frame = json.loads(msg.data)
        if frame.get("op") != "publish":
            continue
        v, w = frame["msg"]["linear"]["x"], frame["msg"]["angular"]["z"]
        seen.append((v, w))
        if not (isinstance(v, float) and isinstance(w, float) and math.isfinite(v) and math.isfinite(w)):
            report.fail(f"non-finite twist reached the robot: {v} {w}")
        elif abs(v) > MAX_LINEAR or abs(w) > MAX_ANGULAR:
            report.fail(f"twist beyond the limits reached the robot: {v} {w}")


async def all_records(http: httpx.AsyncClient, since: int) -> list[dict]:
    out: list[dict] = []
    while True:
        body = (await http.get("/api/latency", params={"since": since, "limit": 10_000})).json()
        out += body["records"]
        if not body["records"] or not body.get("more"):
            return out
        since = body["records"][-1]["rx_seq"]


async def run(bridge_port: int, api: str, count: int, seed: int, huge: int) -> dict:
    rng = random.Random(seed)
    n_env = count // 4
    n_http = count * 3 // 20
    n_frames = count - n_env - n_http - huge - 1
    frames = [frame_case(rng) for _ in range(n_frames)]
    envelopes = [envelope_case(rng, seq) for seq in range(n_env)]
    http_cases = [http_case(rng) for _ in range(n_http)]
    report = Report()
    url = f"ws://127.0.0.1:{bridge_port}/"
    async with httpx.AsyncClient(base_url=api, timeout=10) as http, aiohttp.ClientSession() as session:
        before = (await http.get("/api/health")).json()
        twists: list[tuple[float, float]] = []
        watcher = asyncio.create_task(watch_robot(session, url, twists, report))
        stop, valid_sent = asyncio.Event(), []
        stream = asyncio.create_task(valid_stream(session, url, stop, valid_sent))
        t0 = time.monotonic()
        await fuzz_frames(session, url, frames + [c for c in envelopes if c.expect == "status"], report)
        env_ws = await session.ws_connect(url)
        await env_ws.send_str(
            json.dumps({"op": "advertise", "topic": "/stamped_cmd_vel", "type": "std_msgs/String"})
        )
        for c in envelopes:
            report.count(c.kind)
            await env_ws.send_str(c.payload)
        answers, _ = await collect_answers(env_ws, 1, timeout=1.0)
        if answers:
            report.fail(f"an envelope was answered at the bridge: {answers[0]}")
        await env_ws.close()
        await huge_frames(session, url, huge, report)
        await fuzz_http(api, http_cases, report)
        elapsed = time.monotonic() - t0
        stop.set()
        worst_lag = await stream
        await asyncio.sleep(1.0)
        after = (await http.get("/api/health")).json()
        records = await all_records(http, before["total_seen"])
        watcher.cancel()
    n_bad_env = sum(c.expect == "rejected" for c in envelopes)
    n_ok_env = sum(c.expect == "accepted" for c in envelopes)
    rejected = after["rejected"] - before["rejected"]
    if rejected != n_bad_env:
        report.fail(f"tracker rejected {rejected} envelopes, {n_bad_env} were bad")
    valid_got = [r["seq"] for r in records if isinstance(r.get("seq"), int) and r["seq"] >= VALID_SEQ0]
    if valid_got != valid_sent:
        missing = len(set(valid_sent) - set(valid_got))
        report.fail(f"valid stream: {len(valid_got)} recorded of {len(valid_sent)} ({missing} missing)")
    fuzz_recorded = len(records) - len(valid_got)
    if fuzz_recorded != n_ok_env:
        report.fail(f"{fuzz_recorded} fuzz envelopes recorded, {n_ok_env} were valid")
    total = sum(report.sent.values())
    return {
        "bench": "fuzz",
        "seed": seed,
        "cases": total,
        "by_kind": dict(sorted(report.sent.items())),
        "seconds": round(elapsed, 2),
        "valid_sent": len(valid_sent),
        "valid_recorded": len(valid_got),
        "valid_worst_lag_ms": round(worst_lag * 1000.0, 1),
        "rejected_envelopes": rejected,
        "twists_checked": len(twists),
        "failures": report.failures,
        "ok": not report.failures,
    }


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--count", type=int, default=10_000, help="malformed cases in all (default: 10000)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--huge", type=int, default=3, help="10 MB frames among them (default: 3)")
    args = p.parse_args()
    if args.count < 100:
        p.error("--count must be at least 100")
    log = os.path.join(tempfile.gettempdir(), f"arbiter-fuzz-{os.getpid()}.log")
    backend = EmbeddedBackend.start(0, 0, log_file=log, extra_args=["--max-records", "1000000"])
    try:
        rss0 = rss_kb(backend.proc.pid)
        result = asyncio.run(
            run(backend.bridge_port, f"http://127.0.0.1:{backend.api_port}", args.count, args.seed, args.huge)
        )
        alive = backend.proc.poll() is None
        health = (
            httpx.get(f"http://127.0.0.1:{backend.api_port}/api/health", timeout=5).status_code
            if alive
            else None
        )
        if not alive or health != 200:
            result["failures"].append(f"backend after the run: alive={alive} health={health}")
            result["ok"] = False
        result["backend_rss_kb"] = {"start": rss0, "end": rss_kb(backend.proc.pid)}
    finally:
        backend.stop()
    result["log"] = log
    emit(result)
    return 0 if result["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
