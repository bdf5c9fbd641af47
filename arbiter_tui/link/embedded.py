"""Embedded mode: run the bundled backend as a child process on loopback, like a real deployment."""

from __future__ import annotations

import contextlib
import ctypes
import logging
import os
import select
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

from arbiter_core.listening import parse_listening

log = logging.getLogger(__name__)


class EmbeddedError(RuntimeError):
    pass


def port_free(port: int, host: str = "127.0.0.1") -> bool:
    with socket.socket() as s:
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def _die_with_parent() -> None:  # pragma: no cover - runs in the child
    # Linux: the backend gets SIGTERM if the TUI dies, so a crashed console never leaves it running.
    with contextlib.suppress(Exception):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    os.setpgrp()  # and a terminal's Ctrl-C reaches only the TUI, which stops the robot first


def _spawn(cmd: list[str], timeout: float) -> tuple[subprocess.Popen[str], int, int]:
    """Start the backend and wait for its "listening" line: (process, bridge port, API port)."""
    proc = subprocess.Popen(
        cmd,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None,
    )
    assert proc.stdout is not None
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        ready, _, _ = select.select([proc.stdout], [], [], 0.2)
        if ready:
            line = proc.stdout.readline()
            found = parse_listening(line)
            if found is not None and found.bridge_port is not None:
                return proc, found.bridge_port, found.api_port
        if proc.poll() is not None:
            err = proc.stderr.read().strip() if proc.stderr else ""
            raise EmbeddedError(
                f"the bundled backend exited: {err.splitlines()[-1] if err else proc.returncode}"
            )
    proc.kill()
    raise EmbeddedError(f"the bundled backend did not start within {timeout:.0f} s")


@dataclass
class EmbeddedBackend:
    proc: subprocess.Popen[str]
    bridge_port: int
    api_port: int
    cmd: list[str] = field(default_factory=list)  # how it was started, ports left to fill in
    restarts: int = 0
    _stopping: threading.Event = field(default_factory=threading.Event, repr=False)
    _watcher: threading.Thread | None = field(default=None, repr=False)

    @classmethod
    def start(
        cls,
        bridge_port: int = 9090,
        api_port: int = 8085,
        log_file: str | None = None,
        timeout: float = 15.0,
        transport: str = "embedded",
        extra_args: Sequence[str] = (),
    ) -> EmbeddedBackend:
        bp = bridge_port if bridge_port == 0 or port_free(bridge_port) else 0
        ap = api_port if api_port == 0 or port_free(api_port) else 0
        cmd = [sys.executable, "-m", "arbiter_backend.cli"]
        if transport != "embedded":
            cmd += ["--transport", transport]
        if log_file:
            cmd += ["--log-file", log_file]
        cmd += list(extra_args)
        proc, bp, ap = _spawn([*cmd, "--bridge-port", str(bp), "--api-port", str(ap)], timeout)
        return cls(proc, bp, ap, cmd)

    def supervise(self, interval: float = 0.5) -> None:
        """Restart the backend on the same ports whenever it exits unexpectedly (a crash, an OOM
        kill, someone's ``kill``): the console's link then reconnects by itself."""
        self._watcher = threading.Thread(
            target=self._watch, args=(interval,), name="backend-watch", daemon=True
        )
        self._watcher.start()

    def _watch(self, interval: float) -> None:
        while not self._stopping.wait(interval):
            if self.proc.poll() is None:
                continue
            log.warning("the bundled backend exited (%s); restarting it", self.proc.returncode)
            try:
                ports = ["--bridge-port", str(self.bridge_port), "--api-port", str(self.api_port)]
                proc, _, _ = _spawn([*self.cmd, *ports], 15.0)
            except EmbeddedError as exc:  # e.g. someone else took a port meanwhile: try again next round
                log.warning("restarting the bundled backend failed: %s", exc)
                continue
            if self._stopping.is_set():
                proc.terminate()
                return
            self.proc = proc
            self.restarts += 1

    def stop(self, timeout: float = 5.0) -> None:
        self._stopping.set()
        if self._watcher is not None:
            self._watcher.join(timeout=20)
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        for stream in (self.proc.stdout, self.proc.stderr):
            if stream:
                stream.close()
