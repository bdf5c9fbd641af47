"""``arbiter-tui stats FILE``: the nine AnalyticsStats of a CSV, JSON or MCAP export."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from arbiter_core.cliargs import OneLineParser
from arbiter_core.controllers import MANUAL

from ..analytics import scorecards as SC
from ..analytics.bags import DEFAULT_TOPICS, BagTopics
from ..analytics.exports import Export, ExportFormatError
from ..analytics.grade import Graded, grade
from ..analytics.labels import ERROR_FIELDS, NO_VALUE, format_stat
from ..analytics.model import (
    STATS_FIELDS,
    AnalyticsStats,
    DataPoint,
    columns_of,
    grouped_stats,
    stats_of_points,
)
from ..analytics.observe import ObserveConfig
from ..analytics.runs import RunSummary


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui stats",
        description="Print the nine AnalyticsStats of an arbiter analytics export "
        "(CSV, JSON or MCAP, recognised by content).",
    )
    p.add_argument(
        "file",
        type=Path,
        help="an arbiter_analytics_*.csv, *.json or *.mcap export, or a ros2 bag recorded on the robot (its "
        "directory, split or compressed, with or without metadata.yaml, or a lone .mcap or .db3 file): its "
        "runs from odometry, command, plan, goal, action status and scan topics",
    )
    bag = p.add_argument_group("ros2 bags ('Grade any controller' in docs/analytics.md)")
    for flag, default, kind in (
        ("--odom-topic", DEFAULT_TOPICS.odom, "nav_msgs/Odometry"),
        ("--cmd-topic", DEFAULT_TOPICS.cmd, "geometry_msgs/Twist or TwistStamped"),
        ("--plan-topic", DEFAULT_TOPICS.plan, "nav_msgs/Path"),
    ):
        bag.add_argument(flag, default=default, help=f"{kind} (default %(default)s)")
    bag.add_argument(
        "--goal-topic", default=DEFAULT_TOPICS.goal, help="geometry_msgs/PoseStamped (default %(default)s)"
    )
    bag.add_argument(
        "--status-topic",
        default=DEFAULT_TOPICS.status,
        help="action_msgs/GoalStatusArray of the action that drives: its goal ending ends the run "
        "(default %(default)s)",
    )
    bag.add_argument(
        "--scan-topic",
        default=DEFAULT_TOPICS.scan,
        help="sensor_msgs/LaserScan for the obstacle distances (default %(default)s)",
    )
    bag.add_argument(
        "--label", default="observed", help="what drove: the samples' algorithm (default %(default)s)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object with the seed's camelCase keys")
    p.add_argument(
        "--by",
        choices=("algorithm", "run", "controller"),
        help="one set of stats per group (with --json: an object keyed by group). run: in run order, "
        "headed 'run N ALGORITHM on MISSION' (key 'run N' with 'run', 'algorithm' and 'mission' fields; a "
        "CSV does not carry the mission: null); where the file carries run summaries (JSON and MCAP "
        "exports) each run's stats over all of its samples, as the analytics screen shows them, with 'in "
        "file K/N' when the file holds only part of the run; otherwise over the file's samples; samples "
        "outside every run last, under 'no run'. algorithm: as "
        "the screen groups them, 'ALGORITHM on MISSION' from the file's summaries, else per algorithm over "
        "the file's run samples (samples outside every run belong to no algorithm). controller: each "
        "algorithm's scorecard over all of its runs (Nav2's controller benchmark and the BARN score: "
        "docs/analytics.md, 'Scorecards'). A path length never spans a gap between separate stretches",
    )
    return p


Groups = dict[str, tuple[AnalyticsStats, int | None]]  # name -> (stats, samples in the file when partial)
NO_RUN = "no run"


@dataclass(frozen=True)
class RunLabel:
    """What the file says a run was: its algorithm (from its summary, else from its samples) and its
    mission (summaries only: a CSV does not carry it; "" for manual driving)."""

    run: int
    algorithm: str
    mission: str | None

    def title(self) -> str:
        """``run 3 pure_pursuit on square``, ``run 2 manual``; ``run 4 stanley`` with the mission unknown."""
        on = f" on {self.mission}" if self.mission else ""
        return f"run {self.run} {self.algorithm}{on}"

    def as_dict(self) -> dict[str, object]:
        return {"run": self.run, "algorithm": self.algorithm, "mission": self.mission}


def by_run(export: Export) -> tuple[Groups, dict[str, RunLabel]]:
    """Per run, in run order, then the samples outside every run (``no run``) last, whatever the format:
    the file's summaries where it has them (all samples, partial runs marked), else the file's samples per
    run id. Beside them, each run's algorithm and mission where the file says."""
    points = export.points
    out: Groups = {}
    labels: dict[str, RunLabel] = {}
    if export.runs is not None:
        for r in sorted(export.runs, key=lambda r: r.id):
            out[f"run {r.id}"] = (r.stats, _partial(r.in_ring, r.stats))
            labels[f"run {r.id}"] = RunLabel(r.id, r.algorithm, r.mission)
        names = [NO_RUN if p.runId is None else "" for p in points]
        if NO_RUN in names:
            out[NO_RUN] = (_grouped(points, names)[NO_RUN], None)
        return out, labels
    names = [NO_RUN if p.runId is None else f"run {p.runId}" for p in points]
    grouped = _grouped(points, names)
    algorithms: dict[int, dict[str, None]] = {}
    for p in points:
        if p.runId is not None:
            algorithms.setdefault(p.runId, {})[p.algorithm] = None
    for run_id in sorted(algorithms):
        out[f"run {run_id}"] = (grouped[f"run {run_id}"], None)
        labels[f"run {run_id}"] = RunLabel(run_id, "+".join(algorithms[run_id]), None)
    if NO_RUN in grouped:
        out[NO_RUN] = (grouped[NO_RUN], None)
    return out, labels


def _in_file(part: int | None) -> dict[str, int]:
    return {} if part is None else {"samplesInFile": part}


def _partial(in_file: int, stats: AnalyticsStats) -> int | None:
    return in_file if in_file < stats.sampleCount else None


def by_algorithm(export: Export) -> Groups:
    """As the analytics screen groups them where the file says so, else from the file's run samples."""
    if export.algorithms is not None:
        out: Groups = {}
        for a in export.algorithms:
            name = a.algorithm if a.algorithm == MANUAL or not a.mission else f"{a.algorithm} on {a.mission}"
            mine = [r for r in export.runs or () if (r.algorithm, r.mission) == (a.algorithm, a.mission)]
            out[name] = (a.stats, _partial(sum(r.in_ring for r in mine), a.stats) if mine else None)
        return out
    points = export.points
    if any(p.runId is not None for p in points):
        points = [p for p in points if p.runId is not None]  # idle samples belong to no algorithm
    return {k: (v, None) for k, v in _grouped(points, [p.algorithm for p in points]).items()}


def _grouped(points: list[DataPoint], labels: list[str]) -> dict[str, AnalyticsStats]:
    """``grouped_stats`` over the file's order: a group's path has no step across another group's samples."""
    if not points:
        return {}
    runs = np.fromiter((p.runId or 0 for p in points), dtype=np.int64, count=len(points))
    gaps = np.fromiter((p.gap for p in points), dtype=bool, count=len(points))
    return grouped_stats(columns_of(points), labels, runs, gaps)


def run(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    graded = _graded(args)
    if graded is None:
        return 1
    for note in graded.notes:
        print(f"arbiter-tui stats: {args.file}: warning: {note}", file=sys.stderr)
    export = graded.export
    if not export.points and not export.runs:  # a CSV's header alone: nothing to compute stats of
        print(f"arbiter-tui stats: {args.file}: no samples", file=sys.stderr)
        return 1
    if args.by == "controller":
        return _print_controllers(args, graded)
    labels: dict[str, RunLabel] = {}
    runs = {f"run {r.id}": r for r in export.runs or ()}
    cards = {f"run {c.run}": c for c in graded.cards}
    if args.by is None:
        groups: Groups = {"": (stats_of_points(export.points), None)}
    elif args.by == "run":
        groups, labels = by_run(export)
    else:
        groups = by_algorithm(export)
        if not groups:
            print(f"arbiter-tui stats: {args.file}: {_no_runs(args, graded)}", file=sys.stderr)
            return 1
    why = graded.no_reference  # a recording with no goal or plan: its error stats are none, not 0
    if args.json:
        if args.by is None:
            body: Mapping[str, object] = _stats_json(groups[""][0], why)
        else:
            body = {
                k: _stats_json(v, why)
                | _in_file(part)
                | (labels[k].as_dict() if k in labels else {})
                | _outcome(runs.get(k), json_form=True)
                | ({"scorecard": cards[k].as_dict()} if k in cards and args.by == "run" else {})
                for k, (v, part) in groups.items()
            }
        print(json.dumps(body, allow_nan=False))
        return 0
    width = max(len(f) for f in STATS_FIELDS)
    for group, (stats, part) in groups.items():
        if group:
            note = "" if part is None else f"  in file {part}/{stats.sampleCount} (stats: all its samples)"
            print(f"[{labels[group].title() if group in labels else group}]{note}")
        for name in STATS_FIELDS:
            text = format_stat(name, getattr(stats, name), decimals=6, no_reference=why)
            print(f"{name:<{width}}  {text if text != NO_VALUE else f'{NO_VALUE} ({why})'}")
        for name, value in _outcome(runs.get(group) if args.by == "run" else None).items():
            print(f"{name:<{width}}  {value}")
        if args.by == "run" and group in cards:
            for name, value in _run_card_lines(cards[group]).items():
                print(f"{name:<{width}}  {value}")
    return 0


def _stats_json(stats: AnalyticsStats, no_reference: str) -> dict[str, object]:
    """The seed's nine keys; where there is no reference, the error stats null and ``noReference`` why."""
    body: dict[str, object] = dict(stats.as_dict())
    if no_reference:
        body |= dict.fromkeys(ERROR_FIELDS) | {"noReference": no_reference}
    return body


def _graded(args: argparse.Namespace) -> Graded | None:
    """The file graded, or None after one line on stderr saying why not."""
    topics = BagTopics(
        args.odom_topic, args.cmd_topic, args.plan_topic, args.goal_topic, args.status_topic, args.scan_topic
    )
    try:
        return grade(args.file, topics, ObserveConfig(label=args.label))
    except FileNotFoundError:
        why = "no such file"
    except PermissionError:
        why = "permission denied"
    except (ExportFormatError, OSError) as exc:  # OutOfMemory says so (an ExportFormatError)
        why = str(exc)
    except MemoryError:
        why = "out of memory reading it (the file is not damaged: this machine has too little free memory)"
    print(f"arbiter-tui stats: {args.file}: {why}", file=sys.stderr)
    return None


def _no_runs(args: argparse.Namespace, graded: Graded) -> str:
    if graded.is_bag:
        return (
            f"no runs to group: nothing on {args.goal_topic} or {args.plan_topic} gave the robot a goal "
            "(see --goal-topic, --plan-topic; without --by: the whole recording's stats)"
        )
    return "no runs to group: the file has no samples of a run (without --by: its stats)"


def _print_controllers(args: argparse.Namespace, graded: Graded) -> int:
    """``--by controller``: each algorithm's scorecard over all of its runs."""
    cards = graded.controllers
    if not cards:
        print(f"arbiter-tui stats: {args.file}: {_no_runs(args, graded)}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps({f"controller {c.algorithm}": c.as_dict() for c in cards}, allow_nan=False))
        return 0
    for c in cards:
        print(f"[controller {c.algorithm}: {c.runs} run{'s' * (c.runs != 1)}, {c.successes} succeeded]")
        lines = {"successRate": c.success_rate.text(".3f")} | _card_lines(c)
        width = max(map(len, lines))
        for name, value in lines.items():
            print(f"{name:<{width}}  {value}")
    return 0


def _card_lines(card: SC.RunCard | SC.ControllerCard) -> dict[str, str]:
    o = card.obstacles
    return {
        "timeToGoal": card.time_to_goal_s.text(".3f", " s"),
        "pathLength": card.path_length_m.text(".6f", " m"),
        "linearJerk": card.linear_jerk.text(".6f", " m²/s⁵"),
        "angularJerk": card.angular_jerk.text(".6f", " rad²/s⁵"),
        "minObstacle": o.min_m.text(".6f", " m"),
        "meanMinObstacle": o.mean_min_m.text(".6f", " m"),
        "stdMinObstacle": o.std_min_m.text(".6f", " m"),
        "barnScore": card.barn.text(".6f"),
    }


def _run_card_lines(card: SC.RunCard) -> dict[str, str]:
    """The scorecard figures a run's block does not show already (its outcome and tracking lines do)."""
    lines = _card_lines(card)
    return {k: lines[k] for k in ("minObstacle", "meanMinObstacle", "stdMinObstacle", "barnScore")}


def _outcome(run: RunSummary | None, json_form: bool = False) -> dict[str, object]:
    """A run's outcome, time and path-tracking figures (where the file has them)."""
    if run is None:
        return {}
    if json_form:
        tracking = None if run.tracking is None else run.tracking.as_dict()
        return {"outcome": run.outcome, "time_s": round(run.time_s, 3), "tracking": tracking}
    out: dict[str, object] = {"outcome": run.outcome, "time": f"{run.time_s:.3f} s"}
    if run.tracking is not None:
        t = run.tracking
        out |= {
            "xteMean": f"{t.xte_mean_m:.6f} m",
            "xteRms": f"{t.xte_rms_m:.6f} m",
            "xteP95": f"{t.xte_p95_m:.6f} m",
            "xteMax": f"{t.xte_max_m:.6f} m",
            "pathRatio": "—" if t.path_ratio is None else f"{t.path_ratio:.6f}",
            "meanAbsDwDt": f"{t.mean_abs_dw_dt:.6f} rad/s²",
        }
        if t.linear_jerk is not None and t.angular_jerk is not None:
            out["linearJerk"] = f"{t.linear_jerk:.6f} m²/s⁵"
            out["angularJerk"] = f"{t.angular_jerk:.6f} rad²/s⁵"
        if t.success is not None:
            out["success"] = "yes" if t.success == 1.0 else "no"

    return out
