#!/usr/bin/env python
"""Split each command's one-way latency at the wire: console (stamp -> its packet on the loopback) and
backend (packet -> the tracker's receive time).

The tracker's one-way latency runs from the console's stamp (taken on the link's thread just before the
write) to the tracker's handler. A packet capture on ``lo`` puts a third clock reading between them,
the kernel's, at the moment the frame left the console's socket. All three clocks are this host's.

    tcpdump -i lo -s 600 -w lo.pcap --time-stamp-precision=nano tcp &      # Debian: apt install tcpdump
    python bench/pi.py --size 200x60 --screens control,analytics --records recs.jsonl
    kill %1; python bench/wire_split.py lo.pcap recs.jsonl

A command is matched by its rosbridge ``id`` (``cmd:<seq>``, RosLink's) to the record of the same
``seq``. Client frames are masked (RFC 6455 §5.3): each is unmasked here. Prints, per screen, p50 /
p95 / max of both halves and the six slowest commands. Pure standard library.
"""

from __future__ import annotations

import argparse
import json
import re
import struct
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path

from _common import pct

_ID = re.compile(rb'"id":"cmd:(\d+)"')
_NANO = 0xA1B23C4D
_LINK_HEADER = {1: 14, 113: 16}  # Ethernet (lo shows as one), Linux cooked capture


def tcp_payloads(pcap: bytes) -> Iterator[tuple[float, bytes]]:
    """(capture time in epoch seconds, TCP payload) of each IPv4 packet with one."""
    nano = struct.unpack("<I", pcap[:4])[0] == _NANO
    l2 = _LINK_HEADER.get(struct.unpack("<I", pcap[20:24])[0], 0)
    off = 24
    while off + 16 <= len(pcap):
        sec, frac, incl, _orig = struct.unpack("<IIII", pcap[off : off + 16])
        packet = pcap[off + 16 + l2 : off + 16 + incl]
        off += 16 + incl
        if len(packet) < 20 or packet[0] >> 4 != 4:
            continue
        tcp = packet[(packet[0] & 15) * 4 :]
        if len(tcp) < 20:
            continue
        payload = tcp[(tcp[12] >> 4) * 4 :]
        if payload:
            yield sec + frac / (1e9 if nano else 1e6), payload


def ws_payloads(data: bytes) -> Iterator[bytes]:
    """The (unmasked) payloads of the WebSocket frames a TCP segment starts with; a frame cut by the
    capture's snap length gives what it holds."""
    i = 0
    while i + 2 <= len(data):
        masked, n, j = data[i + 1] & 0x80, data[i + 1] & 0x7F, i + 2
        if n == 126:
            n, j = struct.unpack(">H", data[j : j + 2])[0], j + 2
        elif n == 127:
            n, j = struct.unpack(">Q", data[j : j + 8])[0], j + 8
        body = data[j + (4 if masked else 0) : j + (4 if masked else 0) + n]
        if masked:
            key = data[j : j + 4]
            body = bytes(b ^ key[k % 4] for k, b in enumerate(body))
            j += 4
        yield body
        i = j + n


def wire_times(pcap: bytes) -> dict[int, float]:
    """When each of RosLink's commands (by seq) was first seen on the wire."""
    seen: dict[int, float] = {}
    for ts, payload in tcp_payloads(pcap):
        if payload[:1] not in (b"\x81", b"\x82"):  # a final text or binary frame starts the segment
            continue
        for body in ws_payloads(payload):
            if m := _ID.search(body):
                seen.setdefault(int(m.group(1)), ts)
    return seen


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("pcap", type=Path, help="tcpdump -i lo capture (pcap, micro- or nanosecond)")
    p.add_argument("records", type=Path, help="bench/pi.py --records output (JSON lines)")
    a = p.parse_args()
    wire = wire_times(a.pcap.read_bytes())
    split: dict[tuple[str, str], list[tuple[float, float]]] = defaultdict(list)
    for line in a.records.read_text().splitlines():
        r = json.loads(line)
        if r.get("seq") in wire:
            rx = r["timestamp"]
            stamp = rx - r["latency_ms"] / 1000.0
            at = wire[r["seq"]]
            split[(r["size"], r["screen"])].append(((at - stamp) * 1000.0, (rx - at) * 1000.0))
    for (size, screen), pairs in split.items():
        console, backend = [c for c, _ in pairs], [b for _, b in pairs]
        print(
            f"{size} {screen}: {len(pairs)} commands; console (stamp -> wire) ms p50 {pct(console, 0.5)} "
            f"p95 {pct(console, 0.95)} max {max(console):.2f}; backend (wire -> tracker) ms p50 "
            f"{pct(backend, 0.5)} p95 {pct(backend, 0.95)} max {max(backend):.2f}"
        )
        worst = sorted(pairs, key=lambda cb: -(cb[0] + cb[1]))[:6]
        print("  slowest (console, backend) ms:", ", ".join(f"({c:.1f}, {b:.1f})" for c, b in worst))
    if not split:
        print("no command of the records was found in the capture")
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
