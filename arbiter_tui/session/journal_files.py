"""The journal's files on disk: where they live, which one a running console holds, which ended how, and
keeping the directory under its size bound. No thread, no Textual (``journal.py`` writes them).

A journal is ``<user data dir>/journal/session_<YYYYmmdd-HHMMSS>_<pid>.mcap`` (``platformdirs``: on
Linux ``$XDG_DATA_HOME/arbiter-tui/journal``, by default ``~/.local/share/arbiter-tui/journal``). The
console that writes one holds an exclusive ``flock`` on it for as long as it runs: the kernel lets go
when the process ends however it ends (``kill -9`` included), so "locked" means "a console is writing
it" and nothing is guessed from process ids. How it ended:

* a file without its MCAP end (no footer): the console never closed it (killed, crashed, the power lost);
* a finished file whose end record (``arbiter_journal_end``) says ``signal SIGHUP``/``SIGTERM``: the
  terminal went away (an SSH link dropped) and the console closed it on the way out;
* ``quit``: the person quit. Only the first two are offered at the next start, once: an offered file
  is renamed ``….offered.mcap`` (the same file, kept until the size bound needs its room).
"""

from __future__ import annotations

import contextlib
import os
import time
from dataclasses import dataclass
from pathlib import Path

from ..analytics.exports import JOURNAL_END_METADATA, MCAP_MAGIC, MCAP_POINT_TOPIC, MCAP_RUNS_TOPIC

try:  # POSIX; elsewhere no journal is ever taken for one a console still writes (nothing is offered)
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]  # no locks there: see offerable()

PREFIX = "session_"
OFFERED = ".offered"
SUFFIX = ".mcap"
QUIT = "quit"
CLEARED = "cleared"  # the person cleared the store: the samples after it went on in a new file
FULL = "full"  # past --journal-max-mb: the session went on unjournaled
CLEAN = (QUIT, CLEARED, FULL)  # endings that are no loss: never offered


def default_dir() -> Path:
    from platformdirs import user_data_dir

    return Path(user_data_dir("arbiter-tui", appauthor=False)) / "journal"


def create(directory: Path) -> tuple[int, Path]:
    """A new journal file, made here and nowhere else (``O_EXCL``): its descriptor and path,
    ``session_<local time>_<pid>[_n].mcap``."""
    stem = f"{PREFIX}{time.strftime('%Y%m%d-%H%M%S')}_{os.getpid()}"
    for n in range(1000):
        path = directory / f"{stem}{f'_{n}' if n else ''}{SUFFIX}"
        try:
            return os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644), path
        except FileExistsError:
            continue
    raise FileExistsError(f"no free journal name for {stem} in {directory}")


def lock(fd: int) -> bool:
    """Hold ``fd``'s file for this process (until it ends); False where files cannot be locked."""
    if fcntl is None:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return False
    return True


def held(path: Path) -> bool:
    """A console is writing ``path`` (it holds the lock); True where that cannot be known (no locks)."""
    if fcntl is None:
        return True
    try:
        with path.open("rb") as fh:
            fcntl.flock(fh.fileno(), fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    except OSError:
        return True  # unreadable: leave it alone
    return False


def journals(directory: Path) -> list[Path]:
    """Every journal in ``directory``, oldest first (by modification time)."""
    try:
        found = [p for p in directory.iterdir() if p.name.startswith(PREFIX) and p.name.endswith(SUFFIX)]
    except OSError:
        return []
    return sorted(found, key=mtime)


def mtime(path: Path) -> float:
    """When ``path`` was last written (0 when it cannot be read)."""
    try:
        return path.stat().st_mtime
    except OSError:
        return 0.0


def ending(path: Path) -> str | None:
    """How the session of a journal nobody writes ended: None when the file has no end (killed), else what
    its end record says (``quit``, ``signal SIGHUP``; ``""`` when it has none)."""
    try:
        with path.open("rb") as fh:
            fh.seek(0, os.SEEK_END)
            if fh.tell() < 2 * len(MCAP_MAGIC):
                return None
            fh.seek(-len(MCAP_MAGIC), os.SEEK_END)
            if fh.read() != MCAP_MAGIC:
                return None
            fh.seek(0)
            from mcap.reader import make_reader

            for m in make_reader(fh).iter_metadata():
                if m.name == JOURNAL_END_METADATA:
                    return str(m.metadata.get("ended", ""))
    except Exception:  # a damaged end: as good as none
        return None
    return ""


@dataclass(frozen=True)
class Contents:
    """What a journal holds, counted without decoding its samples: a finished file's samples from its
    summary's statistics and its runs from the runs' own messages; a cut file (no summary) by its
    chunks and the time they span."""

    samples: int | None  # None: a cut file's are not counted (opening it reads them)
    runs: int | None
    chunks: int
    span_s: float

    def words(self) -> str:
        if self.samples is None:
            return f"{self.chunks} chunks ({self.span_s:.0f} s of the session)"
        runs = f", {self.runs} run{'s' * (self.runs != 1)}" if self.runs else ""
        return f"{self.samples} samples{runs}"


def contents(path: Path) -> Contents:
    """``path``'s contents (``Contents``); raises OSError or the mcap library's errors for a damaged one."""
    from mcap.records import Chunk
    from mcap.stream_reader import StreamReader

    with path.open("rb") as fh:
        if ending(path) is not None:  # finished: its summary says
            from mcap.reader import make_reader
            from mcap_ros2.decoder import DecoderFactory

            reader = make_reader(fh, decoder_factories=[DecoderFactory()])
            summary = reader.get_summary()
            if summary is not None and summary.statistics is not None:
                stats = summary.statistics
                topics = {cid: c.topic for cid, c in summary.channels.items()}
                counts = stats.channel_message_counts
                samples = sum(n for cid, n in counts.items() if topics.get(cid) == MCAP_POINT_TOPIC)
                runs = {m.id for _s, _c, _m, m in reader.iter_decoded_messages(topics=[MCAP_RUNS_TOPIC])}
                span = (stats.message_end_time - stats.message_start_time) / 1e9 if samples else 0.0
                return Contents(samples, len(runs), stats.chunk_count, span)
            fh.seek(0)
        chunks, first, last = 0, None, None
        with contextlib.suppress(Exception):  # where a cut file stops
            for record in StreamReader(fh, skip_magic=False, emit_chunks=True).records:
                if isinstance(record, Chunk):
                    chunks += 1
                    first = record.message_start_time if first is None else first
                    last = record.message_end_time
        span = 0.0 if first is None or last is None else max(0, last - first) / 1e9
        return Contents(None, None, chunks, span)


@dataclass(frozen=True)
class Unclean:
    """A journal of a session that did not end by the person's quitting."""

    path: Path
    how: str  # "killed (no end)", "signal SIGHUP"
    older: int = 0  # more such journals found (renamed too, not offered)


def offerable(directory: Path, own: Path | None = None) -> Unclean | None:
    """The newest journal of a session that did not end cleanly and was not offered yet, renamed
    ``….offered.mcap`` (all such journals are, so each is offered once). None when there is none."""
    if fcntl is None:
        return None
    unclean: list[tuple[Path, str]] = []
    for path in journals(directory):
        if path == own or path.name.endswith(OFFERED + SUFFIX) or held(path):
            continue
        how = ending(path)
        if how in CLEAN:
            continue
        unclean.append((path, "killed: its journal has no end" if how is None else how or "unknown"))
    if not unclean:
        return None
    renamed = []
    for path, how in unclean:
        target = path.with_name(path.name[: -len(SUFFIX)] + OFFERED + SUFFIX)
        try:
            path.rename(target)
        except OSError:
            target = path
        renamed.append((target, how))
    newest, how = renamed[-1]
    return Unclean(newest, how, len(renamed) - 1)


def prune(directory: Path, max_bytes: int, keep: tuple[Path | None, ...] = ()) -> int:
    """Delete the oldest journals (never one in ``keep``, never one a console writes) until the directory
    holds at most ``max_bytes`` of them; how many were deleted."""
    files = journals(directory)
    sizes = {p: _size(p) for p in files}
    total = sum(sizes.values())
    deleted = 0
    for path in files:
        if total <= max_bytes:
            break
        if path in keep or held(path):
            continue
        with contextlib.suppress(OSError):
            path.unlink()
            total -= sizes[path]
            deleted += 1
    return deleted


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except OSError:
        return 0
