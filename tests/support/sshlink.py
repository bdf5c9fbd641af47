"""The person on a laptop, the Pi over Wi-Fi: ``arbiter-tui`` run by OpenSSH's server in a network
namespace (the Pi), reached through :mod:`tunlink` (the Wi-Fi link), from a real ``ssh -tt`` client in
tmux (the laptop's terminal) that keys are typed into at a laptop's auto-repeat rate.

What the robot did is read inside the namespace by :mod:`sshlink_probe` (roslibpy on the embedded
backend's rosbridge port, 127.0.0.1 there), stamped with the monotonic clock every namespace shares.
The scenarios (:meth:`SshRig.hold`, :meth:`SshRig.stall_release`, :meth:`SshRig.stop_trial`,
:meth:`SshRig.key_echo`, :meth:`SshRig.screen_bytes`) return figures; the tests assert on them and
``bench/ssh_link.py`` tabulates them.

Root, ``/dev/net/tun``, ``/usr/sbin/sshd``, ``ssh`` and ``tmux`` are needed: :func:`missing` says which
are not there. Everything made (namespace, TUN devices, sshd, the tmux server, the probe) is named per
process and removed on exit.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from .tmux import on_screen
from .tunlink import Impairment, TunLink, unique_subnet, unique_suffix

ROOT = Path(__file__).resolve().parents[2]
SSHD = "/usr/sbin/sshd"
BRIDGE_PORT, API_PORT, SSH_PORT = 9090, 8085, 47022  # inside the namespace: nothing else there
REPEAT_DELAY_S, REPEAT_HZ = 0.25, 30.0  # a laptop's auto-repeat


@dataclass(frozen=True)
class Profile:
    name: str
    link: Impairment  # each way
    about: str


PROFILES = {
    p.name: p
    for p in (
        Profile(
            "lab", Impairment(delay_s=0.030, jitter_s=0.020, loss=0.005), "lab Wi-Fi: 30 ms ± 20, 0.5 % loss"
        ),
        Profile(
            "poor",
            Impairment(delay_s=0.120, jitter_s=0.060, loss=0.03, burst=4.0),
            "poor: 120 ms ± 60, 3 % loss in bursts of 4 packets (mean)",
        ),
        Profile(
            "256k",
            Impairment(delay_s=0.030, jitter_s=0.020, loss=0.005, rate_bps=256_000),
            "256 kbit/s each way (token bucket, 2 s buffer), else lab",
        ),
    )
}
STALL_S = 3.0  # the stall every profile's stall scenario has


def missing() -> str | None:
    """Why the rig cannot run here, or None."""
    if os.geteuid() != 0:
        return "needs root (network namespaces, TUN devices)"
    if not os.path.exists("/dev/net/tun"):
        return "no /dev/net/tun"
    needed = ((SSHD, "openssh-server"), ("ssh", "openssh-client"), ("tmux", "tmux"), ("ip", "iproute2"))
    for exe, what in needed:
        if not (os.path.exists(exe) if exe.startswith("/") else shutil.which(exe)):
            return f"{exe} is not installed ({what})"
    return None


def pct(xs: list[float], q: float) -> float | None:
    if not xs:
        return None
    s = sorted(xs)
    return s[min(len(s) - 1, math.ceil(q * len(s)) - 1)]


@dataclass
class Trace:
    """What the probe saw: commands (t, v, w) and odometry (t, x, y)."""

    cmds: list[tuple[float, float, float]] = field(default_factory=list)
    odom: list[tuple[float, float, float]] = field(default_factory=list)
    up: threading.Event = field(default_factory=threading.Event)

    def cmds_between(self, t0: float, t1: float) -> list[tuple[float, float, float]]:
        return [c for c in list(self.cmds) if t0 <= c[0] <= t1]

    def path_m(self, t0: float, t1: float) -> float:
        pts = [(x, y) for t, x, y in list(self.odom) if t0 <= t <= t1]
        return sum(math.dist(a, b) for a, b in itertools.pairwise(pts))


class SshRig:
    """One namespace, link, sshd, tmux server and console (``console_root``: the checkout to run)."""

    def __init__(self, profile: Profile, console_root: Path = ROOT, size: tuple[int, int] = (80, 24)) -> None:
        self.profile, self.console_root, self.size = profile, console_root, size
        self.suffix = unique_suffix()
        self.host_ip, self.ns_ip = unique_subnet(self.suffix)
        self.netns = f"arbssh{self.suffix}"
        self.session = "laptop"
        self.trace = Trace()
        self._stack = contextlib.ExitStack()

    # -- setup and teardown -------------------------------------------------------------------------
    def __enter__(self) -> SshRig:
        try:
            self._start()
        except BaseException:
            self._stack.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self._stack.close()

    def _start(self) -> None:
        self.tmp = Path(self._stack.enter_context(tempfile.TemporaryDirectory(prefix="arbssh")))
        tag = self.suffix.replace("x", "")[-8:]
        self.link = self._stack.enter_context(
            TunLink(
                self.netns,
                host_ip=self.host_ip,
                ns_ip=self.ns_ip,
                up=self.profile.link,
                down=self.profile.link,
                devices=(f"tsh{tag}", f"tsn{tag}"),
                keep_log=True,
            )
        )
        self._stack.callback(self._kill_namespace_processes)
        self._sshd()
        self._probe()
        self._laptop()

    def _kill_namespace_processes(self) -> None:
        """Whatever still runs in the namespace (sshd's sessions, the console, its backend): started here."""
        out = subprocess.run(["ip", "netns", "pids", self.netns], capture_output=True, text=True).stdout
        for pid in out.split():
            with contextlib.suppress(ProcessLookupError):
                os.kill(int(pid), signal.SIGKILL)

    def _sshd(self) -> None:
        t = self.tmp
        for name in ("host_key", "user_key"):
            subprocess.run(["ssh-keygen", "-q", "-t", "ed25519", "-N", "", "-f", str(t / name)], check=True)
        (t / "authorized_keys").write_text((t / "user_key.pub").read_text())
        (t / "authorized_keys").chmod(0o600)
        Path("/run/sshd").mkdir(mode=0o755, exist_ok=True)  # sshd's privilege separation directory
        (t / "sshd_config").write_text(
            f"Port {SSH_PORT}\nListenAddress {self.ns_ip}\nHostKey {t / 'host_key'}\n"
            f"AuthorizedKeysFile {t / 'authorized_keys'}\nPidFile {t / 'sshd.pid'}\n"
            "PermitRootLogin yes\nPubkeyAuthentication yes\nPasswordAuthentication no\n"
            "KbdInteractiveAuthentication no\nUsePAM no\nStrictModes no\nPrintMotd no\n"
            "PrintLastLog no\nUseDNS no\nSubsystem sftp internal-sftp\n"
        )
        log = (t / "sshd.log").open("w")
        self._stack.callback(log.close)
        sshd = subprocess.Popen(
            ["ip", "netns", "exec", self.netns, SSHD, "-D", "-e", "-f", str(t / "sshd_config")],
            stdout=log,
            stderr=subprocess.STDOUT,
        )
        self._stack.callback(_end, sshd)
        deadline = time.monotonic() + 20
        while True:  # listening, reached from the host through the link
            with contextlib.suppress(OSError), socket.create_connection((self.ns_ip, SSH_PORT), timeout=2):
                break
            if sshd.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"sshd did not start: {(t / 'sshd.log').read_text()}")
            time.sleep(0.1)

    def _probe(self) -> None:
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        cmd = ["ip", "netns", "exec", self.netns, sys.executable, "-u", "-m", "tests.support.sshlink_probe"]
        probe = subprocess.Popen(
            [*cmd, str(BRIDGE_PORT)], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env
        )
        self._stack.callback(_end, probe)
        threading.Thread(target=self._read_probe, args=(probe,), daemon=True).start()

    def _read_probe(self, probe: subprocess.Popen[str]) -> None:
        assert probe.stdout is not None
        for line in probe.stdout:
            m = json.loads(line)
            if m["k"] == "cmd":
                self.trace.cmds.append((m["t"], m["v"], m["w"]))
            elif m["k"] == "odom":
                self.trace.odom.append((m["t"], m["x"], m["y"]))
            else:
                self.trace.up.set()

    def console_command(self) -> str:
        """What sshd runs on the Pi: the console of ``console_root``, the embedded backend on loopback."""
        root, data = self.console_root, self.tmp / "data"
        args = f"--bridge-port {BRIDGE_PORT} --api-port {API_PORT} --export-dir {self.tmp}"
        main = "import sys; from arbiter_tui.cli import main; sys.exit(main())"
        return (
            f"cd {root} && env PYTHONPATH={root} XDG_DATA_HOME={data} XDG_STATE_HOME={data} "
            f"{sys.executable} -c '{main}' {args}"
        )

    def _laptop(self) -> None:
        self.connect()
        self._stack.callback(self.tmux, "kill-server")
        self.screen_until("CONNECTED", 60)
        if not self.trace.up.wait(30):
            raise RuntimeError("the probe never reached the backend")
        deadline = time.monotonic() + 20
        while not self.trace.odom and time.monotonic() < deadline:
            time.sleep(0.05)

    def connect(self) -> None:
        """The laptop's ``ssh -tt`` to the Pi, running the console there, in a new tmux session."""
        t = self.tmp
        ssh = (
            f"ssh -tt -i {t / 'user_key'} -p {SSH_PORT} -o StrictHostKeyChecking=no "
            f"-o UserKnownHostsFile=/dev/null -o LogLevel=ERROR -o BatchMode=yes root@{self.ns_ip} "
            f'"{self.console_command()}"'
        )
        w, h = self.size
        self.tmux("new-session", "-d", "-s", self.session, "-x", str(w), "-y", str(h), ssh)

    def drop(self) -> int:
        """The link drops as the laptop sees it: its ``ssh`` client killed (SIGKILL, nothing said to the
        server); sshd sees the connection end and hangs up on the console (SIGHUP). The client's pid."""
        pane = int(self.tmux("display-message", "-p", "-t", self.session, "#{pane_pid}").strip())
        pid = pane
        if Path(f"/proc/{pane}/comm").read_text().strip() != "ssh":  # a shell that runs it
            children = subprocess.run(["pgrep", "-P", str(pane), "-x", "ssh"], capture_output=True, text=True)
            pid = int(children.stdout.split()[0])
        os.kill(pid, signal.SIGKILL)
        return pid

    def bridge_free(self) -> bool:
        """Nothing listens on the backend's port in the namespace (the console that held it is gone)."""
        out = subprocess.run(
            ["ip", "netns", "exec", self.netns, "ss", "-Htln", f"sport = :{BRIDGE_PORT}"],
            capture_output=True, text=True,
        ).stdout  # fmt: skip
        return not out.strip()

    # -- the laptop's terminal ----------------------------------------------------------------------
    def tmux(self, *args: str) -> str:
        return subprocess.run(
            ["tmux", "-S", str(self.tmp / "tmux"), *args], capture_output=True, text=True, timeout=10
        ).stdout

    def screen(self) -> str:
        return self.tmux("capture-pane", "-p", "-t", self.session)

    def screen_until(self, text: str, timeout: float = 10.0) -> str:
        deadline = time.monotonic() + timeout
        out = ""
        while time.monotonic() < deadline:
            out = self.screen()
            if on_screen(text, out):
                return out
            time.sleep(0.05)
        raise AssertionError(f"{text!r} not on the laptop's screen:\n{out}")

    def key(self, key: str) -> float:
        """Type ``key``; the monotonic time just before tmux got it."""
        t = time.monotonic()
        cmd = ["tmux", "-S", str(self.tmp / "tmux"), "send-keys", "-t", self.session, key]
        subprocess.run(cmd, timeout=10)
        return t

    def hold_keys(
        self, key: str, seconds: float, during: list[tuple[float, Callable[[], object]]] | None = None
    ) -> list[float]:
        """``key`` held for ``seconds``: pressed, then repeated at 30 Hz after 250 ms (the schedule is
        absolute: a slow send-keys does not slow the rate). ``during``: (seconds after the press,
        callable) run at that point of the hold. The send times."""
        t0 = time.monotonic()
        times = [self.key(key)]
        todo = sorted(during or [], key=lambda d: d[0])
        n = 0
        while True:
            at = t0 + REPEAT_DELAY_S + n / REPEAT_HZ
            if at - t0 > seconds:
                break
            while todo and t0 + todo[0][0] <= at:
                _s, act = todo.pop(0)
                act()
            time.sleep(max(0.0, at - time.monotonic()))
            times.append(self.key(key))
            n += 1
        return times

    # -- scenarios ----------------------------------------------------------------------------------
    def settle(self, after: float, quiet_s: float = 0.8, timeout: float = 15.0) -> float:
        """Wait until no moving command has come for ``quiet_s`` (since ``after``); when the last came."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            moving = [c[0] for c in self.trace.cmds_between(after, math.inf) if (c[1], c[2]) != (0.0, 0.0)]
            last = max(moving, default=after)
            if time.monotonic() - last > quiet_s:
                return last
            time.sleep(0.05)
        raise AssertionError("the robot never stopped being commanded")

    def hold(self, seconds: float = 5.0) -> dict[str, float | int | None]:
        """A steady hold of ``i``: the commands' gaps during it (between the first and last moving
        command), the deadman's cut-outs (zeros within it, and a moving command after each), and the
        link's bytes a second toward the laptop meanwhile."""
        b0, t0 = self.link.bytes_in, time.monotonic()
        sent = self.hold_keys("i", seconds)
        bytes_s = (self.link.bytes_in - b0) / (time.monotonic() - t0)
        self.settle(sent[-1])
        cmds = self.trace.cmds_between(sent[0], math.inf)
        moving = [i for i, c in enumerate(cmds) if c[1] != 0.0]
        if not moving:
            raise AssertionError("the held key never moved the robot")
        window = cmds[moving[0] : moving[-1] + 1]
        gaps = [b[0] - a[0] for a, b in itertools.pairwise(window)]
        cutouts = sum(1 for c in window if c[1] == 0.0)
        span = window[-1][0] - window[0][0]
        return {
            "gap_p50_ms": _ms(pct(gaps, 0.5)),
            "gap_p95_ms": _ms(pct(gaps, 0.95)),
            "gap_max_ms": _ms(max(gaps, default=None)),
            "cutouts": cutouts,
            "cutouts_per_min": round(60.0 * cutouts / max(span, 1e-9), 1),
            "hold_span_s": round(span, 2),
            "bytes_per_s_down": round(bytes_s),
        }

    def stall_release(self, before_s: float = 1.5, stall_s: float = STALL_S, held_s: float = 1.0) -> dict:
        """Hold ``i``; ``before_s`` into it the link stalls for ``stall_s``; the person lets go
        ``held_s`` into the stall (they cannot see it). How far the robot goes after the release:
        the path length from odometry, once the link's burst has come and the robot is still."""
        ends: list[float] = []
        stall = (before_s, lambda: ends.append(self.link.stall(stall_s)))
        sent = self.hold_keys("i", before_s + held_s, [stall])
        released = sent[-1]
        last_seq = max((e for r, _d, e in list(self.link.log) if r <= released + 0.05), default=0)
        deadline = time.monotonic() + 20  # the last key's segment delivered (TCP's back-off after the stall)
        while time.monotonic() < deadline and not any(
            d > ends[0] and _seq_after(e, last_seq - 1) for _r, d, e in list(self.link.log)
        ):
            time.sleep(0.05)
        burst_at = time.monotonic()
        self.settle(burst_at, quiet_s=1.0)
        time.sleep(0.3)  # odometry of the last motion
        return {
            "motion_after_release_m": round(self.trace.path_m(released, time.monotonic()), 3),
            "burst_after_stall_end_s": round(burst_at - ends[0], 2),  # TCP's back-off (an upper bound)
        }

    def stop_trial(self, hold_s: float = 1.0) -> float | None:
        """Hold ``i`` for ``hold_s``, then ``k`` in the next repeat's place. From the stop key's arrival
        on the Pi (when the link delivered its TCP segment: the first from the laptop after the key was
        typed that carries new data) to the first zero command, in ms (negative: the deadman's zero
        came first). None when the segment was not seen (the link lost it: its retransmission is then
        the arrival, still found)."""
        sent = self.hold_keys("i", hold_s)
        time.sleep(max(0.0, sent[-1] + 1.0 / REPEAT_HZ - time.monotonic()))
        seq_before = max((e for r, _d, e in list(self.link.log) if r < time.monotonic()), default=0)
        t_k = self.key("k")
        deadline = time.monotonic() + 10
        arrival = None
        while arrival is None and time.monotonic() < deadline:
            arrival = next(
                (d for r, d, e in list(self.link.log) if r >= t_k and _seq_after(e, seq_before)), None
            )
            time.sleep(0.02)
        self.settle(sent[-1], quiet_s=0.6)
        zero = next((c[0] for c in self.trace.cmds_between(t_k, math.inf) if c[1] == 0.0), None)
        if arrival is None or zero is None:
            return None
        return round(1000.0 * (zero - arrival), 1)

    def mission_stall(self, stall_s: float = STALL_S, driving_s: float = 1.0) -> dict[str, float | None]:
        """A mission (``a``: the next controller, ``g``: its mission) driving on its own for ``driving_s``;
        then the link stalls for ``stall_s`` (the person can neither see nor stop it). From the stall's
        start to the first zero command (s; None: it drove on through the stall, the heartbeat's absence)
        and the path driven during the stall (m, odometry). Stopped (space) once the link is back."""
        t_g = self.key("a")
        self.key("g")
        deadline = time.monotonic() + 20

        def driving_since() -> float | None:
            moving = [c[0] for c in self.trace.cmds_between(t_g, math.inf) if (c[1], c[2]) != (0.0, 0.0)]
            return moving[0] if moving else None

        while (first := driving_since()) is None or time.monotonic() - first < driving_s:
            if time.monotonic() > deadline:
                raise AssertionError(f"the mission never drove:\n{self.screen()}")
            time.sleep(0.05)
        t0 = time.monotonic()
        end = self.link.stall(stall_s)
        time.sleep(max(0.0, end - time.monotonic()) + 0.3)  # the stall, and odometry of its last motion
        zero = next((c[0] for c in self.trace.cmds_between(t0, end) if (c[1], c[2]) == (0.0, 0.0)), None)
        driven = self.trace.path_m(t0, end)
        self.key("Space")
        self.settle(end, quiet_s=0.6, timeout=30)  # the stop key over TCP's retransmissions
        return {
            "mission_hold_after_stall_s": None if zero is None else round(zero - t0, 2),
            "driven_during_stall_m": round(driven, 3),
        }

    def key_echo(self, key: str = "q", timeout: float = 5.0) -> float | None:
        """From typing ``key`` (q: faster by 10 %, z: slower) to the laptop's screen showing the new max
        speed, ms; None when it did not show within ``timeout``."""
        before = _speed(self.screen())
        t = self.key(key)
        while time.monotonic() < t + timeout:
            now_speed = _speed(self.screen())
            if now_speed is not None and now_speed != before:
                return round(1000.0 * (time.monotonic() - t), 1)
        return None

    def screen_bytes(self, seconds: float = 3.0) -> float:
        """The link's bytes a second toward the laptop over ``seconds`` of an idle console."""
        b0, t0 = self.link.bytes_in, time.monotonic()
        time.sleep(seconds)
        return round((self.link.bytes_in - b0) / (time.monotonic() - t0))

    def resize(self, width: int, height: int) -> None:
        self.tmux("resize-window", "-t", self.session, "-x", str(width), "-y", str(height))
        self.size = (width, height)
        self.drained()

    def drained(self, timeout: float = 30.0) -> float:
        """Wait until what the console wrote before (a resize's whole-screen repaint, ~50 kB at 200x60)
        has crossed the link: two 1 s windows toward the laptop within 30 % of each other, and, on a
        rate-limited link, below 80 % of its rate (a backlog drains at the full rate). Seconds waited."""
        t0, rate = time.monotonic(), self.profile.link.rate_bps
        last = None
        while time.monotonic() - t0 < timeout:
            b0 = self.link.bytes_in
            time.sleep(1.0)
            window = self.link.bytes_in - b0
            below = rate is None or window * 8 < 0.8 * rate
            if last is not None and below and abs(window - last) <= 0.3 * max(last, window, 1000):
                break
            last = window
        return time.monotonic() - t0


def _seq_after(seq_end: int, before: int) -> bool:
    return 0 < (seq_end - before) % (1 << 32) < (1 << 31)


def _speed(screen: str) -> str | None:
    for word in screen.split("speed ")[1:]:
        return word.split()[0] if word else None
    return None


def _ms(s: float | None) -> float | None:
    return None if s is None else round(1000.0 * s, 1)


def _end(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
