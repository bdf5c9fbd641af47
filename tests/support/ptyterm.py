"""The person's terminal, played by a test: ``arbiter-tui`` in a pseudo-terminal whose other end this
harness reads (counting the bytes the console writes), answering the console's cursor queries
(``ESC [ 6 n`` -> ``ESC [ row ; col R``) as a terminal does, and typing keys. A stalled link is the
harness reading nothing and answering nothing: the console's writes fill the pty, then block."""

import fcntl
import os
import select
import struct
import subprocess
import sys
import termios
import threading
import time

QUERY = b"\x1b[6n"
ANSWER = b"\x1b[1;1R"


class PtyTerminal:
    def __init__(
        self,
        args: list[str],
        cols: int = 100,
        rows: int = 30,
        env: dict[str, str] | None = None,
        program: list[str] | None = None,
    ):
        """``arbiter-tui ARGS`` (or ``program`` + ``args``: another terminal program, a tmux client)."""
        self.master, slave = os.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", rows, cols, 0, 0))
        base = {k: v for k, v in os.environ.items() if k not in ("TMUX", "TMUX_PANE", "STY")}
        base.update(TERM="xterm-256color", COLUMNS=str(cols), LINES=str(rows))
        self.proc = subprocess.Popen(
            [*(program or [sys.executable, "-m", "arbiter_tui.cli"]), *args],
            stdin=slave, stdout=slave, stderr=slave, start_new_session=True, env={**base, **(env or {})},
        )  # fmt: skip
        os.close(slave)
        self.answering = True  # cursor queries answered (a terminal that hears the console)
        self.reading = True  # False: a stalled link (nothing read, nothing answered)
        self.bytes = 0
        self.queries = 0
        self.answered = 0
        self._out = bytearray()
        self._lock = threading.Lock()
        self._closed = False
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        tail = b""
        while not self._closed:
            if not self.reading:
                time.sleep(0.01)
                continue
            ready, _, _ = select.select([self.master], [], [], 0.05)
            if not ready:
                continue
            try:
                data = os.read(self.master, 65536)
            except OSError:
                return
            if not data:
                return
            seen = (tail + data).count(QUERY) - tail.count(QUERY)
            tail = data[-(len(QUERY) - 1) :]
            with self._lock:
                self._out += data
                self.bytes += len(data)
                self.queries += seen
            if seen and self.answering:
                self.answered += seen
                self.type(ANSWER * seen)

    def type(self, data: bytes | str) -> None:
        os.write(self.master, data.encode() if isinstance(data, str) else data)

    def output(self) -> bytes:
        with self._lock:
            return bytes(self._out)

    def mark(self) -> int:
        """Where the output is now: :meth:`since` reads what came after."""
        with self._lock:
            return len(self._out)

    def since(self, mark: int) -> bytes:
        with self._lock:
            return bytes(self._out[mark:])

    def close(self, timeout: float = 10.0) -> int | None:
        self.reading = True
        if self.proc.poll() is None:
            self.type("\x11")  # ctrl+q
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._closed = True
        self._reader.join(2)
        os.close(self.master)
        return self.proc.returncode
