"""A real ``arbiter-backend`` process on free loopback ports, and small waits and probes for tests."""

import os
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass

import httpx

from arbiter_core.listening import parse_listening

from .waits import wait_for


@dataclass
class BackendProc:
    proc: subprocess.Popen
    bridge_port: int
    api_port: int

    @property
    def api(self) -> str:
        return f"http://127.0.0.1:{self.api_port}"

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.returncode


def start_backend(*args: str, timeout: float = 15.0, env: dict[str, str] | None = None) -> BackendProc:
    cmd = [sys.executable, "-m", "arbiter_backend.cli", "--bridge-port", "0", "--api-port", "0", *args]
    proc = subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})},
    )
    deadline = time.monotonic() + timeout
    line = ""
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        found = parse_listening(line)
        if found is not None:
            return BackendProc(proc, found.bridge_port or 0, found.api_port)
        if proc.poll() is not None:
            break
    proc.kill()
    raise RuntimeError(f"backend did not start: {line!r} {proc.stderr.read()}")


def get_json(url: str) -> dict:
    return httpx.get(url, timeout=5).json()


def free_port() -> int:
    """A loopback port nothing listens on (for "the server is down" cases)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


__all__ = ["BackendProc", "free_port", "get_json", "start_backend", "wait_for"]
