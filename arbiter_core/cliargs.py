"""argparse value types shared by ``arbiter-backend`` and ``arbiter-tui``: one clear line per bad value."""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import secrets
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn, TypeVar

from . import topics
from .urls import UrlError, rosbridge_endpoint, tracker_endpoint

# What a TOML config file must give for an option whose argparse type is a given function (the console
# reads its file through these same functions, so one rule decides each value): a number, a whole
# number, or a string of some kind (the default, and the only other TOML type a value may have).
NUMBER = "a number"
WHOLE_NUMBER = "a whole number"
_TAKES: dict[Callable[..., Any], str] = {}


def takes(value_type: Callable[..., Any] | None) -> str:
    """What a config file must give for an option of this argparse type (``NUMBER``, ``WHOLE_NUMBER``
    or a string's description)."""
    if value_type is Path:
        return "a path string"
    return _TAKES.get(value_type, "a string") if value_type is not None else "a string"


_Parse = TypeVar("_Parse", bound=Callable[..., Any])


def _kind(kind: str) -> Callable[[_Parse], _Parse]:
    def mark(fn: _Parse) -> _Parse:
        _TAKES[fn] = kind
        return fn

    return mark


class OneLineParser(argparse.ArgumentParser):
    """argparse that reports a bad command line in one line (``prog: message (see --help)``), exit 2,
    instead of the usage block followed by the error."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: {message} (see --help)\n")


@_kind(WHOLE_NUMBER)
def port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"port must be 0-65535 (0 picks a free one), got {value}")
    return value


def _float(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None


@_kind(NUMBER)
def positive_float(text: str) -> float:
    value = _float(text)
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive finite number, got {text}")
    return value


def bounded_float(low: float, high: float, unit: str = "", low_open: bool = False) -> Callable[[str], float]:
    """An argparse type for a finite number in [low, high] (or (low, high] with ``low_open``); the error
    names the bounds, so a flag and the same key in a config file say the same thing."""
    left = "(" if low_open else "["
    where = f"{left}{low:g}, {high:g}]" + (f" {unit}" if unit else "")

    def parse(text: str) -> float:
        value = _float(text)
        if not math.isfinite(value) or value > high or value < low or (low_open and value == low):
            raise argparse.ArgumentTypeError(f"must be in {where}, got {text}")
        return value

    parse.__name__ = f"number in {where}"  # argparse names the type in some errors
    _TAKES[parse] = NUMBER
    return parse


@_kind(NUMBER)
def non_negative_float(text: str) -> float:
    value = _float(text)
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be zero or a positive finite number, got {text}")
    return value


@_kind(WHOLE_NUMBER)
def count(text: str, high: int = 1_000_000) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if not 1 <= value <= high:
        raise argparse.ArgumentTypeError(f"must be between 1 and {high}, got {value}")
    return value


@_kind("a ws:// or wss:// URL string")
def rosbridge_url(text: str) -> str:
    """A rosbridge URL (``arbiter_core.urls``), kept as written."""
    try:
        rosbridge_endpoint(text, what="URL")
    except UrlError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


@_kind("an http:// or https:// URL string")
def tracker_url(text: str) -> str:
    """A tracker URL (``arbiter_core.urls``), kept as written."""
    try:
        tracker_endpoint(text, what="URL")
    except UrlError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


@_kind("a namespace string")
def namespace(text: str) -> str:
    """A ROS namespace (``/robot1``, or empty for none), kept as written."""
    try:
        topics.namespace(text)
    except topics.TopicNameError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


@_kind("a topic name string")
def topic_name(text: str) -> str:
    """A topic name, relative or absolute (not ``~`` private), kept as written."""
    try:
        topics.resolve(text, what="topic")
    except topics.TopicNameError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


@_kind("a comma-separated string of action names")
def action_names(text: str) -> tuple[str, ...]:
    """Comma-separated ROS action names (relative or absolute); ``""``: none."""
    names = tuple(part.strip() for part in text.split(",") if part.strip())
    for name in names:
        try:
            topics.resolve(name, what="action")
        except topics.TopicNameError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    return names


@_kind("a path string")
def existing_file(text: str) -> Path:
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a directory, not a file")
    if not path.is_file():
        raise argparse.ArgumentTypeError(f"no such file: {text}")
    return path


@_kind("a path string")
def writable_dir(text: str) -> Path:
    """A directory that exists and this user may create files in (files are written there later: an
    export). Creating it is left to the user: a typo should not make a directory."""
    path = Path(text)
    if not path.exists():
        raise argparse.ArgumentTypeError(f"no such directory: {text}")
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a file, not a directory")
    if not can_create_in(path):
        raise argparse.ArgumentTypeError(f"{text}: {NOT_WRITABLE}")
    return path


NOT_WRITABLE = "not writable (this user cannot create files in it)"


def can_create_in(directory: Path) -> bool:
    """Whether a file can be created in ``directory``, tried with an empty file removed at once: the
    permission bits alone pass root in /proc, or on a read-only mount, where the write then fails."""
    if not os.access(directory, os.W_OK | os.X_OK):
        return False
    probe = directory / f".arbiter-write-test-{os.getpid()}-{secrets.token_hex(4)}"
    try:
        os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
    except OSError:
        return False
    with contextlib.suppress(OSError):
        probe.unlink()
    return True


LOG_LEVELS = ("DEBUG", "INFO", "WARNING", "ERROR")


DISTRIBUTIONS = ("arbiter-tui", "arbiter-backend")  # the console's (both commands), the robot's (robot/)


def installed_distribution() -> tuple[str, str] | None:
    """The distribution these modules were installed from and its version (the console's carries both
    commands; a robot may have the backend's alone), or None from a source tree never installed."""
    from importlib.metadata import PackageNotFoundError, version

    for distribution in DISTRIBUTIONS:
        try:
            return distribution, version(distribution)
        except PackageNotFoundError:
            continue
    return None


def add_version(parser: argparse.ArgumentParser) -> None:
    """``--version``: the installed distribution's version."""
    installed = installed_distribution()
    text = "unknown (not installed)" if installed is None else installed[1]
    parser.add_argument("--version", action="version", version=f"{parser.prog} {text}")


def add_log_level(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--log-level",
        type=str.upper,
        choices=LOG_LEVELS,
        default="WARNING",
        help="what the log keeps (default: WARNING)",
    )
