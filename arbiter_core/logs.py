"""Log files both commands write: rotated, one per process unless a path is given, never the terminal."""

from __future__ import annotations

import logging
import logging.handlers
import os
import tempfile
from pathlib import Path

MAX_BYTES = 1_000_000  # rotated at 1 MB, three old files kept: at most 4 MB per process
BACKUPS = 3
FORMAT = "%(asctime)s %(process)d %(name)s %(levelname)s %(message)s"


def default_log_path(program: str) -> Path:
    """``$TMPDIR/<program>-<pid>.log``: instances side by side never write one file."""
    return Path(tempfile.gettempdir()) / f"{program}-{os.getpid()}.log"


def log_to_file(path: str | Path, level: str = "WARNING") -> Path:
    """Send the root logger to a rotating file at ``level``; returns the path."""
    path = Path(path)
    handler = logging.handlers.RotatingFileHandler(
        path, maxBytes=MAX_BYTES, backupCount=BACKUPS, encoding="utf-8"
    )
    handler.setFormatter(logging.Formatter(FORMAT))
    root = logging.getLogger()
    for old in list(root.handlers):
        root.removeHandler(old)
    root.addHandler(handler)
    root.setLevel(level)
    return path
