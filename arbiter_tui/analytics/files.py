"""Export files on disk: atomic, never overwriting, and read back for ``arbiter-tui stats``."""

from __future__ import annotations

import contextlib
import json
import os
import stat
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from .exports import (
    MCAP_MAGIC,
    Export,
    ExportFormatError,
    parse_csv,
    read_json,
    read_mcap,
    to_csv,
    to_json,
    to_mcap,
)
from .model import AnalyticsStats
from .runs import AlgorithmSummary, RunSummary
from .store import AnalyticsStore, DataPoint

FORMATS = ("csv", "json", "mcap")
MAX_IMPORT_BYTES = 512 * 1024 * 1024


class ExportError(OSError):
    """Writing an export failed; nothing partial was left behind."""


def _umask() -> int:
    """The process's umask, read without changing it (Linux), else by setting and restoring it."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_new_file(directory: Path, stem: str, suffix: str, data: bytes) -> Path:
    """Write ``data`` to ``directory/stem.suffix`` atomically and without overwriting.

    The bytes go to a temporary file in the same directory, are flushed to disk,
    and are then hard-linked under the final name, which fails rather than
    replace an existing file; on a clash ``_1``, ``_2``... are appended to the stem.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise ExportError(f"export directory {directory} does not exist")
    try:
        return _write_new_file(directory, stem, suffix, data)
    except ExportError:
        raise
    except OSError as exc:  # e.g. a directory that lists but takes no files (/proc/1), a full disk
        raise ExportError(f"cannot write export to {directory}: {exc.strerror or exc}") from exc


def _write_new_file(directory: Path, stem: str, suffix: str, data: bytes) -> Path:
    fd, tmp = tempfile.mkstemp(prefix=f".{stem}.", suffix=".tmp", dir=directory)
    try:
        # mkstemp makes the file 0600; an export is an ordinary file: 0666 less the umask, as open() gives
        os.fchmod(fd, 0o666 & ~_umask())
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        for attempt in range(1000):
            final = directory / (f"{stem}{'' if attempt == 0 else f'_{attempt}'}.{suffix}")
            try:
                os.link(tmp, final)
            except FileExistsError:
                continue
            except OSError:
                # Filesystems without hard links: exclusive create, then replace the empty placeholder.
                try:
                    with open(final, "xb"):
                        pass
                except FileExistsError:
                    continue
                os.replace(tmp, final)
            return final
        raise ExportError(f"could not find a free file name for {stem}.{suffix}")
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


class NothingToExport(ExportError):
    """The store holds no samples: an export would be a header and nothing else."""


def export_stem(clock_ms: Callable[[], int] = lambda: time.time_ns() // 1_000_000) -> str:
    return f"arbiter_analytics_{clock_ms()}"


@dataclass(frozen=True, slots=True)
class Collected:
    """What an export writes, taken from the store at one moment (the chooser says its count, and the
    file then holds exactly those samples, however many were recorded since)."""

    points: list[DataPoint]
    stats: AnalyticsStats
    runs: tuple[RunSummary, ...]
    algorithms: tuple[AlgorithmSummary, ...]


def collected(store: AnalyticsStore) -> Collected:
    """The store's samples, stats, runs and algorithms now (the caller holds off the recorder)."""
    return Collected(store.points(), store.stats(), store.runs(), store.runs_by_algorithm())


def export_store(
    store: AnalyticsStore | Collected,
    fmt: str,
    directory: Path,
    clock_ms: Callable[[], int] = lambda: time.time_ns() // 1_000_000,
    stem: str | None = None,
) -> Path:
    """Export the store's points (or what was ``collected`` from it) as ``arbiter_analytics_<epoch
    ms>.<fmt>`` (or ``stem.<fmt>``: one stem for the formats written together); the store is untouched.
    Refuses (``NothingToExport``) when there are no samples."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown export format {fmt!r}; choose from {', '.join(FORMATS)}")
    got = store if isinstance(store, Collected) else collected(store)
    points, stats, runs, algorithms = got.points, got.stats, got.runs, got.algorithms
    if not points:
        raise NothingToExport("nothing to export: 0 samples (drive, or start a mission with g, first)")
    if fmt == "csv":
        data = to_csv(points).encode()
    elif fmt == "json":
        data = to_json(points, stats, runs, algorithms).encode()
    else:
        data = to_mcap(points, stats, runs, algorithms)
    return write_new_file(Path(directory), stem or export_stem(clock_ms), fmt, data)


def load_points(path: Path) -> list[DataPoint]:
    """Read a CSV, JSON or MCAP export (chosen by content, not by name)."""
    return load_export(path).points


def load_export(path: Path) -> Export:
    """Read a CSV, JSON or MCAP export (chosen by content, not by name), with its summaries if any."""
    path = Path(path)
    try:
        st = path.stat()
        if stat.S_ISDIR(st.st_mode):
            raise IsADirectoryError(str(path))
        if not stat.S_ISREG(st.st_mode):  # a FIFO or a device would block or never end
            raise ExportFormatError(f"{path} is not a regular file")
        size = st.st_size
        if size > MAX_IMPORT_BYTES:
            raise ExportFormatError(f"file is {size} bytes, larger than {MAX_IMPORT_BYTES}")
        raw = path.read_bytes()
    except IsADirectoryError:
        raise ExportFormatError(f"{path} is a directory") from None
    if raw.startswith(MCAP_MAGIC):
        return read_mcap(raw)
    if not raw.strip():
        raise ExportFormatError("empty file" if not raw else "empty file: only blank lines")
    for magic, what in _NOT_EXPORTS:
        if raw.startswith(magic):
            raise ExportFormatError(f"{what}, not a CSV, JSON or MCAP export")
    try:
        if b"\0" in raw[:4096]:
            raise UnicodeDecodeError("utf-8", raw, 0, 1, "NUL byte")
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        head = raw[:8].hex(" ")
        raise ExportFormatError(f"binary data (starts {head}), not a CSV, JSON or MCAP export") from None
    stripped = text.lstrip("\ufeff \t\r\n")
    if stripped.startswith(("{", "[")) or _is_json_scalar(stripped):
        return read_json(text)
    return Export(parse_csv(text))


# files people mistake for an export, by their first bytes
_NOT_EXPORTS = (
    (b"\x1f\x8b", "gzip-compressed data (gunzip it first)"),
    (b"\x28\xb5\x2f\xfd", "zstd-compressed data (unzstd it first)"),
    (b"PK\x03\x04", "a zip archive (unzip it first)"),
    (b"SQLite format 3\0", "an SQLite database (a ROS 2 .db3 bag?)"),
    (b"\xff\xfe", "UTF-16 text (save it as UTF-8)"),
    (b"\xfe\xff", "UTF-16 text (save it as UTF-8)"),
)


def _is_json_scalar(text: str) -> bool:
    """``42``, ``"x"``, ``true``: JSON, so said to be JSON rather than a CSV with an odd header."""
    try:
        json.loads(text)
    except ValueError:
        return False
    return True
