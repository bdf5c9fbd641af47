"""A point-to-point IP link into a network namespace that behaves like a Wi-Fi link, in user space.

For a kernel without ``sch_netem`` (``tc qdisc ... netem`` answers "Specified qdisc kind is unknown"):
two TUN devices, one in this namespace and one moved into ``netns``, and a thread that carries every IP
packet from one to the other. Each direction has its own :class:`Impairment`:

* **delay and jitter**: a packet's delay is drawn from a normal distribution (``delay_s`` ±
  ``jitter_s``, one standard deviation, never below zero), but it never leaves before the packet ahead
  of it in the same direction (FIFO): a Wi-Fi link delays a packet in the access point's queue and
  retries it in the air, and what is queued behind it waits, so the delays bunch but TCP sees the
  order it sent (a reordering link would be a different, rarer, fault);
* **loss**: Gilbert-Elliott, a good state that loses ``loss`` of its packets and a bad one that loses
  all; ``burst`` > 1 is the mean length of a bad state in packets (the bursts a microwave oven or a
  roaming client give), with the good-to-bad rate chosen so that the mean loss is still ``loss``;
  ``burst`` = 1 is independent loss per packet;
* **a rate limit**: a token bucket (``rate_bps``, a bucket of ``bucket_bytes``) shapes each direction;
  what waits for tokens queues (FIFO) up to ``queue_s`` of the rate, and the tail beyond that is dropped,
  as a router's buffer does;
* **stalls** (:meth:`TunLink.stall`): nothing crosses, either way, for the stall's length. What arrives
  meanwhile, and what was in flight, is *dropped*, not held: a Wi-Fi link that loses its peer retries
  each frame a few times (milliseconds) and then drops it, so after a stall it is TCP's retransmission,
  backing off from its 200 ms RTO (0.2, 0.4, 0.8, 1.6 s...), that brings the data back, all at once and
  up to one back-off *after* the link returned. Holding the packets would deliver them at the stall's
  end, a kinder and less true burst. ``stall(..., hold=True)`` holds them instead, for comparison.

The kernels at both ends see a real lossy, slow link. Root only. The devices and the namespace are
named per process (and per link within it) so that concurrent runs do not collide, and are removed on
exit. ``bytes_in``/``bytes_out`` count the IP bytes delivered from/to the namespace (headers included);
``log`` (when ``keep_log``) has every data-carrying TCP segment from the host: (read, delivered, seq end).

    with TunLink("fleetbot", delay_s=0.2, loss=0.05) as link:   # host 10.201.0.1 <-> 10.201.0.2 in netns
        ...; link.bytes_in
"""

from __future__ import annotations

import collections
import fcntl
import itertools
import os
import random
import select
import struct
import subprocess
import threading
import time
from dataclasses import dataclass

TUNSETIFF = 0x400454CA
IFF_TUN, IFF_NO_PI = 0x0001, 0x1000
_links = itertools.count()


def _open_tun(name: str) -> int:
    fd = os.open("/dev/net/tun", os.O_RDWR)
    fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", name.encode(), IFF_TUN | IFF_NO_PI))
    return fd


def _sh(*cmd: str) -> None:
    subprocess.run(cmd, check=True, capture_output=True)


def unique_suffix() -> str:
    """This process's pid and a counter: names and subnets no other run uses at the same time."""
    return f"{os.getpid()}x{next(_links)}"


def unique_subnet(suffix: str) -> tuple[str, str]:
    """A /30's two addresses for a link named by ``suffix`` (10.205-10.220.x.y, from the pid and counter)."""
    pid, n = (int(p) for p in suffix.split("x"))
    key = (pid * 8 + n) % (16 * 256 * 64)
    a, b, c = 205 + key // (256 * 64), (key // 64) % 256, (key % 64) * 4
    return f"10.{a}.{b}.{c + 1}", f"10.{a}.{b}.{c + 2}"


@dataclass(frozen=True)
class Impairment:
    """One direction of the link (the module's docstring says what each does)."""

    delay_s: float = 0.0
    jitter_s: float = 0.0
    loss: float = 0.0
    burst: float = 1.0  # mean packets in a burst of loss (Gilbert-Elliott's bad state); 1: independent
    rate_bps: float | None = None  # bits a second; None: no limit
    bucket_bytes: int = 3000  # the token bucket's depth: two full packets may go back to back
    queue_s: float = 2.0  # the rate limiter's buffer, in seconds of the rate (drop-tail beyond)

    def __post_init__(self) -> None:
        if not 0.0 <= self.loss < 1.0 or self.burst < 1.0 or self.delay_s < 0 or self.jitter_s < 0:
            raise ValueError(f"bad impairment {self}")


class _Direction:
    """The state of one direction: the loss chain, the bucket, the FIFO's last departure, the queue."""

    def __init__(self, imp: Impairment, rng: random.Random) -> None:
        self.imp, self.rng = imp, rng
        self.queue: collections.deque[tuple[float, float, bytes]] = collections.deque()  # (due, read, pkt)
        self.bad = False
        self.last_due = 0.0
        self.tokens, self.tokens_at, self.send_at = float(imp.bucket_bytes), 0.0, 0.0
        if imp.burst > 1.0 and imp.loss > 0.0:  # Gilbert: bad loses all, good none; mean loss = loss
            self.p_bad_good = 1.0 / imp.burst
            self.p_good_bad = imp.loss * self.p_bad_good / (1.0 - imp.loss)
        else:
            self.p_bad_good = self.p_good_bad = 0.0

    def lost(self) -> bool:
        imp = self.imp
        if self.p_good_bad == 0.0:
            return self.rng.random() < imp.loss
        draw = self.rng.random()
        self.bad = draw >= self.p_bad_good if self.bad else draw < self.p_good_bad
        return self.bad

    def departure(self, now: float, size: int) -> float | None:
        """When the rate limiter lets ``size`` bytes go (now without a limit); None: its buffer is full."""
        rate = self.imp.rate_bps
        if rate is None:
            return now
        bytes_s = rate / 8.0
        t = max(now, self.send_at)
        if t - now > self.imp.queue_s:
            return None
        self.tokens = min(float(self.imp.bucket_bytes), self.tokens + (t - self.tokens_at) * bytes_s)
        if self.tokens < size:
            t += (size - self.tokens) / bytes_s
            self.tokens = float(size)
        self.tokens -= size
        self.tokens_at = self.send_at = t
        return t

    def due(self, depart: float) -> float:
        imp = self.imp
        delay = max(0.0, self.rng.gauss(imp.delay_s, imp.jitter_s)) if imp.jitter_s else imp.delay_s
        self.last_due = max(depart + delay, self.last_due)  # FIFO: never before the packet ahead
        return self.last_due


def tcp_seq_end(packet: bytes) -> int | None:
    """The sequence number after a TCP segment's payload (IPv4), None when it carries none."""
    if len(packet) < 40 or packet[0] >> 4 != 4 or packet[9] != 6:
        return None
    ihl = (packet[0] & 0x0F) * 4
    total = struct.unpack_from("!H", packet, 2)[0]
    doff = (packet[ihl + 12] >> 4) * 4
    payload = total - ihl - doff
    if payload <= 0:
        return None
    return (struct.unpack_from("!I", packet, ihl + 4)[0] + payload) % (1 << 32)


class TunLink:
    def __init__(
        self,
        netns: str,
        delay_s: float = 0.0,
        loss: float = 0.0,
        host_ip: str = "10.201.0.1",
        ns_ip: str = "10.201.0.2",
        seed: int = 1,
        *,
        up: Impairment | None = None,
        down: Impairment | None = None,
        devices: tuple[str, str] | None = None,
        keep_log: bool = False,
    ) -> None:
        """``up``: host -> namespace, ``down``: namespace -> host; each defaults to ``delay_s``/``loss``."""
        plain = Impairment(delay_s=delay_s, loss=loss)
        self.netns, self.host_ip, self.ns_ip = netns, host_ip, ns_ip
        self.rng = random.Random(seed)
        self.up, self.down = up or plain, down or plain
        self.devices = devices or (f"tunfh{os.getpid() % 100000}", f"tunfb{os.getpid() % 100000}")
        self.bytes_in = self.bytes_out = 0  # from / to the namespace, as delivered
        self.dropped = self.packets = 0
        self.keep_log = keep_log
        self.log: list[tuple[float, float, int]] = []  # host's data segments: (read, delivered, seq end)
        self._stall_until, self._stall_hold = 0.0, False
        self._lock = threading.Lock()
        self._stop = threading.Event()

    def stall(self, seconds: float, hold: bool = False) -> float:
        """Nothing crosses either way for ``seconds`` from now (dropped; held with ``hold``); its end."""
        with self._lock:
            self._stall_until, self._stall_hold = time.monotonic() + seconds, hold
            return self._stall_until

    def __enter__(self) -> TunLink:
        host_dev, ns_dev = self.devices
        subprocess.run(["ip", "netns", "del", self.netns], capture_output=True)
        _sh("ip", "netns", "add", self.netns)
        try:
            self.host_fd, self.ns_fd = _open_tun(host_dev), _open_tun(ns_dev)
            _sh("ip", "link", "set", ns_dev, "netns", self.netns)
            _sh("ip", "addr", "add", self.host_ip, "peer", self.ns_ip, "dev", host_dev)
            _sh("ip", "link", "set", host_dev, "up")
            inside = ("ip", "netns", "exec", self.netns)
            _sh(*inside, "ip", "addr", "add", self.ns_ip, "peer", self.host_ip, "dev", ns_dev)
            _sh(*inside, "ip", "link", "set", ns_dev, "up")
            _sh(*inside, "ip", "link", "set", "lo", "up")
        except BaseException:
            self._teardown()
            raise
        self._thread = threading.Thread(target=self._run, name="tunlink", daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(2)
        self._teardown()

    def _teardown(self) -> None:
        for fd in (getattr(self, "host_fd", None), getattr(self, "ns_fd", None)):
            if fd is not None:
                os.close(fd)  # the host's device goes with its last descriptor (not persistent)
        subprocess.run(["ip", "netns", "del", self.netns], capture_output=True)

    def _run(self) -> None:
        # a packet read from the host's device goes up (into the namespace), and the reverse
        dirs = {self.host_fd: _Direction(self.up, self.rng), self.ns_fd: _Direction(self.down, self.rng)}
        out = {self.host_fd: self.ns_fd, self.ns_fd: self.host_fd}
        while not self._stop.is_set():
            now = time.monotonic()
            with self._lock:
                held_until = self._stall_until if self._stall_hold else 0.0
            due = [max(d.queue[0][0], held_until) for d in dirs.values() if d.queue]
            timeout = max(0.0, min(due) - now) if due else 0.1
            ready, _, _ = select.select(list(dirs), [], [], min(timeout, 0.1))
            now = time.monotonic()
            with self._lock:
                stalled, hold = now < self._stall_until, self._stall_hold
            for fd in ready:
                packet = os.read(fd, 65535)
                self.packets += 1
                d = dirs[fd]
                depart = None if (stalled and not hold) or d.lost() else d.departure(now, len(packet))
                if depart is None:
                    self.dropped += 1
                    continue
                d.queue.append((d.due(depart), now, packet))
            for fd, d in dirs.items():
                while d.queue and d.queue[0][0] <= now:
                    if stalled and hold:
                        break
                    _due, read_at, packet = d.queue.popleft()
                    if stalled:  # in flight when the link went: lost
                        self.dropped += 1
                        continue
                    os.write(out[fd], packet)
                    if fd == self.ns_fd:
                        self.bytes_in += len(packet)
                    else:
                        self.bytes_out += len(packet)
                        if self.keep_log and (end := tcp_seq_end(packet)) is not None:
                            self.log.append((read_at, now, end))
