"""argparse value types shared by ``arbiter-backend`` and ``arbiter-tui``: one clear line per bad value."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import NoReturn


class OneLineParser(argparse.ArgumentParser):
    """argparse that reports a bad command line in one line (``prog: message (see --help)``), exit 2,
    instead of the usage block followed by the error."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: {message} (see --help)\n")


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
    return parse


def non_negative_float(text: str) -> float:
    value = _float(text)
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be zero or a positive finite number, got {text}")
    return value


def count(text: str, high: int = 1_000_000) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if not 1 <= value <= high:
        raise argparse.ArgumentTypeError(f"must be between 1 and {high}, got {value}")
    return value


LOG_LEVELS = ("DEBUG", "INFO", "WARNING", "ERROR")


def add_version(parser: argparse.ArgumentParser, distribution: str = "arbiter-tui") -> None:
    """``--version``: the installed package's version (one distribution carries both commands)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        text = version(distribution)
    except PackageNotFoundError:  # running from a source tree that was never installed
        text = "unknown (not installed)"
    parser.add_argument("--version", action="version", version=f"{parser.prog} {text}")


def add_log_level(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--log-level",
        type=str.upper,
        choices=LOG_LEVELS,
        default="WARNING",
        help="what the log keeps (default: WARNING)",
    )
