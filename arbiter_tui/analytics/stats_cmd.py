"""``arbiter-tui stats FILE``: the nine AnalyticsStats of a CSV, JSON or MCAP export."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from arbiter_core.cliargs import OneLineParser

from .exports import ExportFormatError
from .files import load_points
from .labels import format_stat
from .store import STATS_FIELDS, stats_of_points


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui stats",
        description="Print the nine AnalyticsStats of an arbiter analytics export "
        "(CSV, JSON or MCAP, recognised by content).",
    )
    p.add_argument("file", type=Path, help="an arbiter_analytics_*.csv, *.json or *.mcap export")
    p.add_argument("--json", action="store_true", help="print one JSON object with the seed's camelCase keys")
    return p


def run(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    try:
        points = load_points(args.file)
    except FileNotFoundError:
        print(f"arbiter-tui stats: {args.file}: no such file", file=sys.stderr)
        return 1
    except PermissionError:
        print(f"arbiter-tui stats: {args.file}: permission denied", file=sys.stderr)
        return 1
    except (ExportFormatError, OSError) as exc:
        print(f"arbiter-tui stats: {args.file}: {exc}", file=sys.stderr)
        return 1
    stats = stats_of_points(points)
    if args.json:
        print(json.dumps(stats.as_dict(), allow_nan=False))
        return 0
    width = max(len(f) for f in STATS_FIELDS)
    for name in STATS_FIELDS:
        print(f"{name:<{width}}  {format_stat(name, getattr(stats, name), decimals=6)}")
    return 0
