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
from .store import STATS_FIELDS, AnalyticsStats, AnalyticsStore, DataPoint, stats_of_points


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui stats",
        description="Print the nine AnalyticsStats of an arbiter analytics export "
        "(CSV, JSON or MCAP, recognised by content).",
    )
    p.add_argument("file", type=Path, help="an arbiter_analytics_*.csv, *.json or *.mcap export")
    p.add_argument("--json", action="store_true", help="print one JSON object with the seed's camelCase keys")
    p.add_argument(
        "--by",
        choices=("algorithm", "run"),
        help="one set of stats per group (with --json: an object keyed by group). algorithm: path length "
        "counts only steps between consecutive samples of the same algorithm. run: by the runId exports "
        "carry (key 'run N'; samples outside every run under 'no run'), each run's stats over the samples "
        "the file holds",
    )
    return p


def by_run(points: list[DataPoint]) -> dict[str, AnalyticsStats]:
    """Stats per run id, in order of first appearance; samples without one under "no run"."""
    grouped: dict[str, list[DataPoint]] = {}
    for p in points:
        grouped.setdefault("no run" if p.runId is None else f"run {p.runId}", []).append(p)
    return {name: stats_of_points(pts) for name, pts in grouped.items()}


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
    if args.by is None:
        groups = {"": stats_of_points(points)}
    elif args.by == "run":
        groups = by_run(points)
    else:
        store = AnalyticsStore(max_data_points=max(1, len(points)))
        store.start_collection()
        for point in points:
            store.record(point)
        groups = store.stats_by_algorithm()
    if args.json:
        body = groups[""].as_dict() if args.by is None else {k: v.as_dict() for k, v in groups.items()}
        print(json.dumps(body, allow_nan=False))
        return 0
    width = max(len(f) for f in STATS_FIELDS)
    for group, stats in groups.items():
        if group:
            print(f"[{group}]")
        for name in STATS_FIELDS:
            print(f"{name:<{width}}  {format_stat(name, getattr(stats, name), decimals=6)}")
    return 0
