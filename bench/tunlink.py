"""A point-to-point IP link into a network namespace that delays and drops packets, in user space.

For a kernel without ``sch_netem`` (``tc qdisc ... netem`` answers "Specified qdisc kind is unknown"):
two TUN devices, one in this namespace and one moved into ``netns``, and a thread that carries every IP
packet from one to the other ``delay_s`` later, dropping each with probability ``loss``, independently
per packet and per direction. The kernels at both ends see a real lossy, slow link: TCP retransmits,
backs off and reorders nothing (a constant delay keeps the order). Root only.

    with TunLink("fleetbot", delay_s=0.2, loss=0.05) as link:   # host 10.201.0.1 <-> 10.201.0.2 in netns
        ...; link.bytes_in  # IP bytes that came from the namespace's side (headers included)
"""

from __future__ import annotations

import collections
import fcntl
import os
import random
import select
import struct
import subprocess
import threading
import time

TUNSETIFF = 0x400454CA
IFF_TUN, IFF_NO_PI = 0x0001, 0x1000


def _open_tun(name: str) -> int:
    fd = os.open("/dev/net/tun", os.O_RDWR)
    fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", name.encode(), IFF_TUN | IFF_NO_PI))
    return fd


def _sh(*cmd: str) -> None:
    subprocess.run(cmd, check=True, capture_output=True)


class TunLink:
    def __init__(
        self,
        netns: str,
        delay_s: float,
        loss: float,
        host_ip: str = "10.201.0.1",
        ns_ip: str = "10.201.0.2",
        seed: int = 1,
    ) -> None:
        self.netns, self.delay_s, self.loss = netns, delay_s, loss
        self.host_ip, self.ns_ip = host_ip, ns_ip
        self.rng = random.Random(seed)
        self.bytes_in = self.bytes_out = 0  # from / to the namespace, as forwarded (after the drops)
        self.dropped = self.packets = 0
        self._stop = threading.Event()

    def __enter__(self) -> TunLink:
        subprocess.run(["ip", "netns", "del", self.netns], capture_output=True)
        _sh("ip", "netns", "add", self.netns)
        self.host_fd, self.ns_fd = _open_tun("tunfh0"), _open_tun("tunfb0")
        _sh("ip", "link", "set", "tunfb0", "netns", self.netns)
        _sh("ip", "addr", "add", self.host_ip, "peer", self.ns_ip, "dev", "tunfh0")
        _sh("ip", "link", "set", "tunfh0", "up")
        inside = ("ip", "netns", "exec", self.netns)
        _sh(*inside, "ip", "addr", "add", self.ns_ip, "peer", self.host_ip, "dev", "tunfb0")
        _sh(*inside, "ip", "link", "set", "tunfb0", "up")
        _sh(*inside, "ip", "link", "set", "lo", "up")
        self._thread = threading.Thread(target=self._run, name="tunlink", daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(2)
        os.close(self.host_fd)
        os.close(self.ns_fd)
        subprocess.run(["ip", "netns", "del", self.netns], capture_output=True)

    def _run(self) -> None:
        other = {self.host_fd: self.ns_fd, self.ns_fd: self.host_fd}
        queues: dict[int, collections.deque] = {
            self.host_fd: collections.deque(),
            self.ns_fd: collections.deque(),
        }
        while not self._stop.is_set():
            now = time.monotonic()
            due = [q[0][0] for q in queues.values() if q]
            timeout = max(0.0, min(due) - now) if due else 0.1
            ready, _, _ = select.select([self.host_fd, self.ns_fd], [], [], min(timeout, 0.1))
            now = time.monotonic()
            for fd in ready:
                packet = os.read(fd, 65535)
                self.packets += 1
                if self.rng.random() < self.loss:
                    self.dropped += 1
                    continue
                queues[other[fd]].append((now + self.delay_s, packet))
                if fd == self.ns_fd:
                    self.bytes_in += len(packet)
                else:
                    self.bytes_out += len(packet)
            for fd, q in queues.items():
                while q and q[0][0] <= now:
                    os.write(fd, q.popleft()[1])
