"""Export files on disk: atomic, never overwriting, and read back for ``arbiter-tui stats``."""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from .exports import (
    MCAP_MAGIC,
    ExportFormatError,
    parse_csv,
    parse_json,
    parse_mcap,
    to_csv,
    to_json,
    to_mcap,
)
from .store import AnalyticsStore, DataPoint

FORMATS = ("csv", "json", "mcap")
MAX_IMPORT_BYTES = 512 * 1024 * 1024


class ExportError(OSError):
    """Writing an export failed; nothing partial was left behind."""


def write_new_file(directory: Path, stem: str, suffix: str, data: bytes) -> Path:
    """Write ``data`` to ``directory/stem.suffix`` atomically and without overwriting.

    The bytes go to a temporary file in the same directory, are flushed to disk,
    and are then hard-linked under the final name, which fails rather than
    replace an existing file; on a clash ``_1``, ``_2``... are appended to the stem.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise ExportError(f"export directory {directory} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{stem}.", suffix=".tmp", dir=directory)
    try:
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


def export_store(
    store: AnalyticsStore,
    fmt: str,
    directory: Path,
    clock_ms: Callable[[], int] = lambda: time.time_ns() // 1_000_000,
) -> Path:
    """Export the store's points as ``arbiter_analytics_<epoch ms>.<fmt>``; the store is untouched."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown export format {fmt!r}; choose from {', '.join(FORMATS)}")
    points = store.points()
    stats = store.stats()
    runs = store.runs()
    if fmt == "csv":
        data = to_csv(points).encode()
    elif fmt == "json":
        data = to_json(points, stats, runs).encode()
    else:
        data = to_mcap(points, stats, runs)
    try:
        return write_new_file(Path(directory), f"arbiter_analytics_{clock_ms()}", fmt, data)
    except ExportError:
        raise
    except OSError as exc:
        raise ExportError(f"cannot write export to {directory}: {exc.strerror or exc}") from exc


def load_points(path: Path) -> list[DataPoint]:
    """Read a CSV, JSON or MCAP export (chosen by content, not by name)."""
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
        return parse_mcap(raw)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ExportFormatError("not a CSV, JSON or MCAP export") from None
    stripped = text.lstrip("\ufeff \t\r\n")
    if stripped.startswith("{"):
        return parse_json(text)
    return parse_csv(text)
