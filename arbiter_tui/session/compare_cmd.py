"""``arbiter-tui compare``: every algorithm on every mission in simulated time, ranked; CI-friendly."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from arbiter_core.cliargs import OneLineParser, positive_float
from arbiter_core.kinematics import DEFAULT_LIMITS

from ..analytics import ranking
from ..analytics.exports import to_csv, to_json, to_mcap
from ..analytics.files import ExportError, write_new_file
from ..analytics.runs import row_of
from ..analytics.store import stats_of_points
from ..control.teleop import cap_setting
from ..settings import Settings
from .compare import AUTONOMOUS, MISSION_NAMES, CompareError, RunResult, compare, parse_names, ranking_of

D = Settings()  # the console's defaults, one place


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui compare",
        description="Run control algorithms on missions in the client-side simulator, in simulated time "
        "(seconds, not minutes), and rank them: " + ranking.RULE + ".",
    )
    p.add_argument(
        "--mission", default=",".join(MISSION_NAMES), help=f"comma-separated ({', '.join(MISSION_NAMES)})"
    )
    p.add_argument(
        "--algorithms", default=",".join(AUTONOMOUS), help=f"comma-separated ({', '.join(AUTONOMOUS)})"
    )
    p.add_argument(
        "--speed", type=positive_float, default=D.speed, help=f"max speed of controllers, m/s ({D.speed:g})"
    )
    p.add_argument("--turn", type=positive_float, default=D.turn, help=f"max turn rate, rad/s ({D.turn:g})")
    p.add_argument(
        "--json",
        action="store_true",
        help="one JSON object: runs, missions (each ranked), overall (best, the missions it is over, mean "
        "ranks, wins, rule), best, rule",
    )
    p.add_argument("--export-dir", type=Path, help="also write every run's data points as CSV, JSON and MCAP")
    return p


HEAD = ("rank", "algorithm", "done", "time s", "final e_d m", "avg e_d m", "p95 e_d m", "max |v| m/s")


def table(results: list[RunResult]) -> str:
    """One ranked block per mission, then the overall answer and the rule."""
    answer = ranking_of(results)
    groups = ranking.by_mission(results)
    rows: list[list[str]] = []
    for m in answer.missions:
        rows.append([m.mission])
        rows.append(list(HEAD))
        for i, r in enumerate(groups[m.mission], 1):
            mark = " *" if i == 1 and r.completed else ""
            rows.append([
                f"{i}{mark}", r.algorithm, "yes" if r.completed else "NO", f"{r.time_s:.1f}",
                f"{r.final_error_m:.3f}", f"{r.stats.avgDistanceError:.3f}", f"{r.stats.p95Error:.3f}",
                f"{r.max_linear_vel:.3f}",
            ])  # fmt: skip
        rows.extend([["", name, "not run"] for name in m.not_run])
    cells = [r for r in rows if len(r) > 1]
    widths = [max((len(r[c]) for r in cells if c < len(r)), default=0) for c in range(len(HEAD))]
    lines = []
    for row in rows:
        if len(row) == 1:
            lines.append(row[0])
            continue
        lines.append("  " + "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=False)).rstrip())
    lines.append(f"* {ranking.RULE_MISSION}")
    lines.append(f"{ranking.RULE_OVERALL}: {answer.overall.reason}")
    return "\n".join(lines)


def export(results: list[RunResult], directory: Path) -> list[Path]:
    points = [p for r in results for p in r.points]
    runs = [r.summary for r in results if r.summary is not None]
    rows = [row_of(r) for r in runs]  # one run per (mission, algorithm)
    stats = stats_of_points(points)
    stem = f"arbiter_compare_{time.time_ns() // 1_000_000}"
    return [
        write_new_file(directory, stem, "csv", to_csv(points).encode()),
        write_new_file(directory, stem, "json", to_json(points, stats, runs, rows).encode()),
        write_new_file(directory, stem, "mcap", to_mcap(points, stats, runs, rows)),
    ]


def run(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    try:
        missions = parse_names(args.mission, MISSION_NAMES, "mission")
        algorithms = parse_names(args.algorithms, AUTONOMOUS, "algorithms")
    except CompareError as exc:
        print(f"arbiter-tui compare: {exc}", file=sys.stderr)
        return 2
    if args.export_dir is not None and not args.export_dir.is_dir():
        print(f"arbiter-tui compare: --export-dir {args.export_dir} is not a directory", file=sys.stderr)
        return 2
    speed, note = cap_setting("speed", args.speed, DEFAULT_LIMITS.max_linear, "m/s")
    turn, note_turn = cap_setting("turn", args.turn, DEFAULT_LIMITS.max_angular, "rad/s")
    for line in (note, note_turn):
        if line:
            print(f"arbiter-tui compare: {line}", file=sys.stderr)
    results = compare(missions, algorithms, speed, turn)
    written: list[Path] = []
    if args.export_dir is not None:
        try:
            written = export(results, args.export_dir)
        except ExportError as exc:
            print(f"arbiter-tui compare: {exc}", file=sys.stderr)
            return 1
    answer = ranking_of(results)
    if args.json:
        groups = ranking.by_mission(results)
        body = {
            "runs": [r.as_dict() for r in results],
            "missions": [
                {
                    "mission": m.mission,
                    "best": m.best,
                    "ranking": [{"rank": i, **r.as_dict()} for i, r in enumerate(groups[m.mission], 1)],
                    "not_run": list(m.not_run),
                }
                for m in answer.missions
            ],
            "overall": answer.overall.as_dict(),
            "best": None if answer.overall.best is None else {"algorithm": answer.overall.best},
            "rule": ranking.RULE,
            "exports": [str(p) for p in written],
        }
        print(json.dumps(body, allow_nan=False))
    else:
        print(table(results))
        for path in written:
            print(f"wrote {path}")
    return 0
