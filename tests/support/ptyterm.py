"""The person's terminal, played by a test: ``arbiter-tui`` in a pseudo-terminal whose other end this
harness reads (counting the bytes the console writes), answering the console's cursor queries
(``ESC [ 6 n`` -> ``ESC [ row ; col R``) as a terminal does, and typing keys. A stalled link is the
harness reading nothing and answering nothing: the console's writes fill the pty, then block; a slow
link is the harness reading at its rate (``rate``)."""

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
        # a slow link with sshd's deep buffers (bytes a second; None: none): everything is read at once
        # (the buffers take it) and reaches the person's screen at this rate, in order; the terminal
        # answers a query when the query reaches it
        self.rate: float | None = None
        self._link_free = 0.0  # when the link has carried everything read so far
        self._arrivals: list[tuple[int, float]] = []  # (output offset a chunk ends at, when it is on screen)
        self._answers: list[float] = []  # when owed answers are due (a query on screen)
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
            self._answer_due()
            ready, _, _ = select.select([self.master], [], [], 0.005 if self._answers else 0.05)
            if not ready:
                continue
            try:
                data = os.read(self.master, 65536)
            except OSError:
                return
            if not data:
                return
            now, rate = time.monotonic(), self.rate
            seen = (tail + data).count(QUERY) - tail.count(QUERY)
            tail = data[-(len(QUERY) - 1) :]
            with self._lock:
                self._out += data
                self.bytes += len(data)
                self.queries += seen
                if rate is not None:
                    self._link_free = max(self._link_free, now) + len(data) / rate
                    self._arrivals.append((len(self._out), self._link_free))
            if seen and self.answering:
                self._answers += [now if rate is None else self._link_free] * seen
                self._answer_due()

    def _answer_due(self) -> None:
        now = time.monotonic()
        due = [t for t in self._answers if t <= now]
        if due:
            self._answers = [t for t in self._answers if t > now]
            self.answered += len(due)
            self.type(ANSWER * len(due))

    def backlog_s(self) -> float:
        """How long the slow link needs to carry what it holds now."""
        return max(0.0, self._link_free - time.monotonic())

    def on_screen_at(self, offset: int) -> float:
        """When the output up to ``offset`` reached the person's screen (through the slow link, if any)."""
        with self._lock:
            for end, at in self._arrivals:
                if end >= offset:
                    return at
        return time.monotonic()

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
