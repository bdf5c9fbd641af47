"""The session's journal: what the console records, on disk as it goes, so that a dropped link, a
``kill -9``, a crash or a power cut loses at most the last second.

What: every sample (the store's DataPoints, with the odometry beside them, as an MCAP export has
them), every run's summary and every per-(mission, algorithm) row each time it changes (a reader keeps
the last of each), the tracker's latency window (each command's latency as it is polled) and the
console's own link figures (each matched command's round trip, one-way and corrected delay), and each
run's reference path (plan) when a new one is in force (``/arbiter/plans``). How: an
MCAP file written in zstd chunks by the export's own channel set (``exports.McapChannels``), one chunk
every ``FLUSH_S`` (0.5 s) handed to the kernel and fsync'ed, so what ``kill -9`` or a power cut leaves
is a file whose whole chunks are all there; ``arbiter-tui stats`` and screen 2's ``f`` read such a file
up to its last chunk (``exports.recover_journal``) and read a finished one as any export. Why MCAP and
not rotated CSV or JSON lines: it is the format the product already reads with its runs and their
summaries (a CSV carries no run outcomes or missions), Foxglove opens it, and one file holds the
samples, the runs and the link's figures with their message definitions.

Where: ``journal_files`` (the user data directory, one file a session, a lock while it is written).
The work is done on a thread of its own, off the UI and off the command path: it copies what it needs
from the store and the meter under their own locks (the new samples, and every few seconds the runs:
a running run's samples, ~1 ms for an hour of them at 10 Hz) and computes the runs' summaries and
writes outside them; the session's lock is never taken. A full disk, an unwritable directory, a file
grown past its bound: one line said (``warn``), the journal stops, the console goes on.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from ..analytics.exports import JOURNAL_END_METADATA, JOURNAL_METADATA, McapChannels
from ..analytics.runs import AlgorithmSummary, RunSummary
from ..analytics.store import AnalyticsStore, paths_in_force, runs_copy
from ..latency.clocksync import Sample
from . import journal_files as F

log = logging.getLogger(__name__)

FLUSH_S = 0.5  # a chunk handed to the kernel (and synced) at least this often
CLOSE_WAIT_S = 2.0  # close() waits at most this long for the thread and the file (a stalled disk)
# The run summaries: at once when a run begins or ends, else this often. A running run's summary is
# computed over all its samples (2-8 ms for an hour's run on the dev box, several times that on a Pi;
# on a copy, outside the store's lock): not every chunk.
RUNS_EVERY_S = 5.0
LATENCY_TOPIC = "/arbiter/latency"
LATENCY_TYPE = "arbiter_msgs/msg/Latency"
LATENCY_DEF = "float64 timestamp  # when the tracker received the command, epoch s\nfloat64 latency_ms"
LINK_TOPIC = "/arbiter/link"
LINK_TYPE = "arbiter_msgs/msg/LinkSample"
LINK_DEF = "\n".join(
    [
        "float64 timestamp  # when the report came back, epoch s",
        "uint64 seq  # the command's",
        "float64 rtt_ms",
        "float64 raw_ms  # one-way, the two clocks as they are",
        "float64 corrected_ms  # one-way, with the clock offset as the console estimated it then",
        "float64 delay_ms  # the round trip less the tracker's holding time; NaN: not said",
    ]
)


@dataclass(frozen=True)
class Found:
    """What the start found of a session that did not end cleanly: said once, opened with one key."""

    path: Path
    how: str
    contents: F.Contents | None  # None: it could not be read
    older: int

    def text(self) -> str:
        when = time.strftime("%H:%M %d %b", time.localtime(F.mtime(self.path) or time.time()))
        more = f" ({self.older} older ones beside it)" if self.older else ""
        kept = "nothing readable" if self.contents is None else self.contents.words()
        return (
            f"The session last written at {when} did not end cleanly ({self.how}): its journal kept "
            f"{kept}. R opens it on screen 2. {self.path}{more}"
        )


@dataclass(frozen=True)
class Sources:
    """What the journal reads, each under its owner's lock: the store, and the link's meter samples (None
    where the link has no meter); the tracker's latency window is fed to it (:meth:`Journal.latency`)."""

    store: AnalyticsStore
    link_samples: Callable[[], list[Sample]] | None = None


class Journal:
    def __init__(
        self,
        sources: Sources,
        directory: Path,
        max_bytes: int,
        warn: Callable[[str], None] = lambda text: None,
        found: Callable[[Found], None] = lambda f: None,
        flush_s: float = FLUSH_S,
    ) -> None:
        self.sources = sources
        self.directory = directory
        self.max_bytes = max_bytes
        self.warn = warn
        self.found = found
        self.flush_s = flush_s
        self.path: Path | None = None
        self.written = 0  # samples journaled (tests and the bench read it)
        self._file: IO[bytes] | None = None
        self._channels: McapChannels | None = None
        self._schemas: dict[str, Any] = {}
        self._lock = threading.Lock()  # the writer: the thread's steps, close() from the UI's thread
        self._wake = threading.Event()  # set: close() was called (the thread stops, opens nothing)
        self._stopped = False  # the journal writes no more (closed, failed, full): nothing is queued
        self._thread: threading.Thread | None = None
        self._total = 0
        self._clears = 0
        self._runs: dict[int, RunSummary] = {}
        self._active: int | None = None  # the store's active run when the summaries were last written
        self._runs_at = -math.inf
        self._rows: dict[tuple[str, str], AlgorithmSummary] = {}
        self._plans: dict[int, Any] = {}  # each run's path last written (the array: a replan replaces it)
        self._latency: deque[tuple[float, float]] = deque()  # the poller's thread appends, the step takes
        self._latency_t = -math.inf  # the poller's thread alone
        self.offered: Found | None = None  # what the start found of a session that did not end cleanly
        self._link_at = -math.inf
        self._mono_to_epoch = time.time() - time.monotonic()

    # -- life ----------------------------------------------------------------------------------
    def start(self) -> None:
        """Open this session's file and write on a thread of its own (what a previous session left is
        looked for there first: ``found``)."""
        self._thread = threading.Thread(target=self._run, name="journal", daemon=True)
        self._thread.start()

    def close(self, ended: str = F.QUIT) -> None:
        """The last samples written and the file finished, saying how the session ended. Idempotent."""
        self._wake.set()
        self._stopped = True
        self._latency.clear()
        thread, self._thread = self._thread, None
        deadline = time.monotonic() + CLOSE_WAIT_S  # a quit, a hang-up: never longer than this
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=CLOSE_WAIT_S)
        wait = max(0.0, deadline - time.monotonic())
        if not self._lock.acquire(timeout=wait):  # the thread is stuck in a write or an fsync
            log.warning("journal: %s not finished: its disk did not answer in %g s", self.path, CLOSE_WAIT_S)
            return  # the file stays as it is: read up to its last chunk
        try:
            if self._channels is None:
                return
            try:
                self._step(force=True)
                self._channels.metadata(JOURNAL_END_METADATA, {"ended": ended})
                self._channels.finish()
                self._sync()
            except Exception as exc:  # the file stays as it is: read up to its last chunk
                log.warning("journal: could not finish %s: %s", self.path, exc)
            self._shut()
        finally:
            self._lock.release()

    def latency(self, window_t: tuple[float, ...], window: tuple[float, ...]) -> None:
        """The tracker's latency window as polled (receive times, epoch s; latencies, ms): the records
        newer than the last one journaled are written with the next chunk. One caller thread (the
        poller's: the UI's loop); it never waits for the journal's thread (no lock: a deque). Nothing
        is kept once the journal stopped (closed, full, failed): nobody would take it."""
        if self._stopped:
            return
        fresh = [(t, v) for t, v in zip(window_t, window, strict=False) if t > self._latency_t]
        if fresh:
            self._latency.extend(fresh)
            self._latency_t = fresh[-1][0]

    def _run(self) -> None:
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            self._look_back()
            with self._lock:
                if self._wake.is_set():  # closed while looking back: no file that nobody finishes
                    self._stopped = True
                    return
                self._open()
        except OSError as exc:
            self._fail(f"no journal this session: {self.directory}: {exc.strerror or exc}")
            return
        except Exception as exc:  # the mcap library missing what the journal needs, say
            log.exception("journal: cannot start")
            self._fail(f"no journal this session: {exc}")
            return
        while not self._wake.wait(self.flush_s):
            with self._lock:
                if self._channels is None:
                    return
                try:
                    self._step()
                    self._sync()
                except Exception as exc:  # a full disk (OSError), or anything else: said, never raised
                    if not isinstance(exc, OSError):
                        log.exception("journal: a step failed")
                    why = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
                    self._fail(f"journal stopped ({why}): {self.path}; export to keep the rest")
                    self._shut()
                    return
                if self._file is not None and self._file.tell() >= self.max_bytes:
                    self._fail(
                        f"journal full ({self.max_bytes / 1e6:g} MB, --journal-max-mb): the rest of this "
                        f"session is not journaled; export to keep it. {self.path}"
                    )
                    try:
                        self._channels.metadata(JOURNAL_END_METADATA, {"ended": F.FULL})
                        self._channels.finish()
                        self._sync()
                    except Exception as exc:  # the file stays as it is: read up to its last chunk
                        log.warning("journal: could not finish %s: %s", self.path, exc)
                    self._shut()
                    return

    def _look_back(self) -> None:
        unclean = F.offerable(self.directory)
        if unclean is not None:
            contents: F.Contents | None = None
            try:
                contents = F.contents(unclean.path)  # counted, not decoded (R decodes it)
            except Exception as exc:
                log.warning("journal: cannot read %s: %s", unclean.path, exc)
            self.offered = Found(unclean.path, unclean.how, contents, unclean.older)
            self.found(self.offered)
        F.prune(self.directory, self.max_bytes, keep=(None if unclean is None else unclean.path,))

    def _open(self) -> None:
        fd, path = F.create(self.directory)
        F.lock(fd)
        self._file = _stream(fd)
        self.path = path
        channels = McapChannels(self._file)
        if not callable(getattr(channels.writer._writer, "flush", None)):
            raise RuntimeError("the installed mcap library cannot flush a chunk (mcap >= 1.2 needed)")
        channels.metadata(JOURNAL_METADATA, {"pid": str(os.getpid()), "started": time.strftime("%FT%T%z")})
        w = channels.writer
        self._schemas = {
            LATENCY_TOPIC: w.register_msgdef(LATENCY_TYPE, LATENCY_DEF),
            LINK_TOPIC: w.register_msgdef(LINK_TYPE, LINK_DEF),
        }
        self._channels = channels
        self._clears = self.sources.store.clears
        channels.flush()
        self._sync()

    def _fail(self, text: str) -> None:
        self._stopped = True
        self._latency.clear()
        log.warning("journal: %s", text)
        self.warn(text)

    def _shut(self) -> None:
        self._channels = None
        if self._file is not None:
            with contextlib.suppress(OSError):
                self._file.close()  # the lock goes with it
            self._file = None

    def _sync(self) -> None:
        if self._file is not None:
            self._file.flush()
            os.fsync(self._file.fileno())

    # -- one chunk (under self._lock) ----------------------------------------------------------
    def _step(self, force: bool = False) -> None:
        channels = self._channels
        assert channels is not None
        store = self.sources.store
        if store.clears != self._clears:  # the person cleared the store: the runs start again at 1
            self._rotate()
            channels = self._channels
            assert channels is not None
        points, self._total = store.points_since(self._total)
        for p in points:
            channels.point(p)
        self.written += len(points)
        active, now = store.active_run, time.monotonic()
        if force or active != self._active or now - self._runs_at >= RUNS_EVERY_S:
            self._active, self._runs_at = active, now
            self._summaries(channels, int(points[-1].timestamp * 1e6) if points else time.time_ns())
        w = channels.writer
        schema = self._schemas[LATENCY_TOPIC]
        while self._latency:
            t, v = self._latency.popleft()
            t_ns = int(t * 1e9)
            row = {"timestamp": t, "latency_ms": v}
            w.write_message(LATENCY_TOPIC, schema, row, log_time=t_ns, publish_time=t_ns)
        self._link(w)
        self._plans_changed(channels)
        channels.flush()

    def _plans_changed(self, channels: McapChannels) -> None:
        """Each run's reference path, when it is new since the last chunk (a replan within one flush
        replaced by another is not written: the one in force is)."""
        for run_id, path in paths_in_force(self.sources.store):
            if self._plans.get(run_id) is not path:
                self._plans[run_id] = path
                channels.plan(run_id, time.time() * 1000.0, path[:, :2].tolist())

    def _summaries(self, channels: McapChannels, t_ns: int) -> None:
        """The runs and per-(mission, algorithm) rows that changed since they were last written."""
        runs = runs_copy(self.sources.store)  # copied under the store's lock, computed outside it
        for r in runs.summaries():
            if self._runs.get(r.id) != r:
                channels.run(r)
                self._runs[r.id] = r
        for a in runs.by_algorithm():
            if self._rows.get((a.mission, a.algorithm)) != a:
                channels.algorithm(a, t_ns)
                self._rows[(a.mission, a.algorithm)] = a

    def _link(self, w: Any) -> None:
        read = self.sources.link_samples
        if read is None:
            return
        for s in read():
            if s.at_s <= self._link_at or math.isnan(s.at_s):
                continue
            self._link_at = s.at_s
            t = s.at_s + self._mono_to_epoch
            row = {"timestamp": t, "seq": s.seq, "rtt_ms": s.rtt_ms, "raw_ms": s.raw_ms,
                   "corrected_ms": s.corrected_ms, "delay_ms": s.delay_ms}  # fmt: skip
            t_ns = int(t * 1e9)
            w.write_message(LINK_TOPIC, self._schemas[LINK_TOPIC], row, log_time=t_ns, publish_time=t_ns)

    def _rotate(self) -> None:
        """After a clear: this file is finished ("cleared") and a new one takes the samples from now."""
        assert self._channels is not None
        self._channels.metadata(JOURNAL_END_METADATA, {"ended": F.CLEARED})
        self._channels.finish()
        self._sync()
        self._shut()
        self._runs.clear()
        self._rows.clear()
        self._plans.clear()
        self._runs_at = -math.inf  # the summaries again, in the new file
        self._open()


def _stream(fd: int) -> IO[bytes]:
    """The journal file's stream (a test hands it one that fills up)."""
    return os.fdopen(fd, "wb")
