"""``arbiter-tui stats FILE``: the nine AnalyticsStats of a CSV or JSON export."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from arbiter_backend.cliargs import OneLineParser
from arbiter_backend.core.analytics import STATS_FIELDS, stats_of_points
from arbiter_backend.core.exports import ExportFormatError
from arbiter_backend.files import load_points

UNITS = {
    "sampleCount": "",
    "avgLinearVel": "m/s",
    "avgAngularVel": "rad/s",
    "maxLinearVel": "m/s",
    "avgDistanceError": "m",
    "avgHeadingError": "rad",
    "stdDevError": "m",
    "p95Error": "m",
    "totalPathLength": "m",
}


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui stats",
        description="Print the nine AnalyticsStats of an arbiter analytics export (CSV or JSON).",
    )
    p.add_argument("file", type=Path, help="an arbiter_analytics_*.csv or *.json export")
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
        value = getattr(stats, name)
        text = str(value) if name == "sampleCount" else f"{value:.6f}"
        print(f"{name:<{width}}  {text} {UNITS[name]}".rstrip())
    return 0
