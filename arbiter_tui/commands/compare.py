"""``arbiter-tui compare``: every algorithm on every mission in simulated time, ranked; CI-friendly."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from arbiter_core.cliargs import OneLineParser, count, non_negative_float, positive_float, writable_dir
from arbiter_core.kinematics import DEFAULT_LIMITS
from arbiter_core.linkmodel import LinkModel, LinkModelError
from arbiter_core.record import LatencyRecord, RecordError
from arbiter_core.stats import percentile

from ..analytics import ranking
from ..analytics.exports import to_csv, to_json, to_mcap
from ..analytics.files import ExportError, load_points, write_new_file
from ..analytics.runs import row_of
from ..analytics.store import stats_of_points
from ..control.teleop import cap_setting
from ..session import trials as TR
from ..session.compare import (
    AUTONOMOUS,
    CMD_TIMEOUT_S,
    MISSION_NAMES,
    CompareError,
    RunResult,
    compare,
    parse_names,
    ranking_of,
)
from ..session.settings import Settings
from ..session.trials import INTERVAL, VERDICT_RULE
from .tracker_args import DEFAULT_TRACKER

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
    p.add_argument(
        "--export-dir",
        type=writable_dir,
        help="also write every run's data points as CSV, JSON and MCAP there (an existing directory you "
        "can write to); a sweep: one set per latency and trial",
    )
    link = p.add_argument_group(
        "a modelled link (in simulated time): commands reach the robot late, some never; odometry "
        "reaches the console late"
    )
    link.add_argument(
        "--latency",
        metavar="MS[,MS...]|measured",
        help="one-way command latency, ms; several values run the whole comparison once per value (a "
        "sweep); 'measured': the p50 and p95 of the latencies of --measured-from",
    )
    link.add_argument(
        "--measured-from",
        default=DEFAULT_TRACKER,
        metavar="URL|FILE",
        help=f"with --latency measured: a tracker (its newest {MEASURED_RECORDS} records) or an analytics "
        f"export (JSON, CSV or MCAP; its latencyMs) (default {DEFAULT_TRACKER})",
    )
    link.add_argument(
        "--jitter", type=non_negative_float, default=0.0, metavar="MS",
        help="extra delay per command: |N(0, MS)| (half-normal), in order (default 0)",
    )  # fmt: skip
    link.add_argument(
        "--loss", type=non_negative_float, default=0.0, metavar="FRACTION",
        help="fraction of commands dropped, below 1 (default 0)",
    )  # fmt: skip
    link.add_argument(
        "--odom-delay", type=non_negative_float, default=0.0, metavar="MS",
        help="how late odometry reaches the console, ms (default 0)",
    )  # fmt: skip
    link.add_argument("--seed", type=int, default=0, help="seed of the jitter and loss draws (default 0)")
    link.add_argument(
        "--trials", type=count, default=1, metavar="N",
        help="run every cell N times, each with jitter and loss drawn from its own seed; figures become "
        f"the {INTERVAL.replace('%', '%%')}, and a mission's best is named only when {VERDICT_RULE} "
        "(default 1)",  # argparse formats help with %: the interval's "95 %" must be "95 %%" here
    )  # fmt: skip
    link.add_argument(
        "--cmd-timeout", type=positive_float, default=CMD_TIMEOUT_S, metavar="S",
        help=f"the simulated robot stops when no command has arrived for S seconds, as the backend's "
        f"(default {CMD_TIMEOUT_S:g})",
    )  # fmt: skip
    p.add_argument(
        "--plot", type=Path, metavar="FILE",
        help="with a sweep: also draw avg cross-track error against latency, one panel per mission, one "
        "line per controller (with its 95 %% interval), as FILE.svg or FILE.png (matplotlib)",
    )  # fmt: skip
    return p


MEASURED_RECORDS = 1000


def measured_latencies(source: str, timeout: float = 5.0) -> list[float]:
    """[p50, p95] of the one-way latencies a tracker holds (``http(s)://``) or an export file carries, in
    ms (the product's percentile rule); a negative one (clocks apart) counts as 0: a link is never early."""
    values: list[float] = []
    if source.startswith(("http://", "https://")):
        import httpx

        try:
            resp = httpx.get(
                f"{source.rstrip('/')}/api/latency", params={"limit": MEASURED_RECORDS}, timeout=timeout
            )
            resp.raise_for_status()
            records = resp.json().get("records", [])
        except (httpx.HTTPError, ValueError, AttributeError) as exc:
            raise CompareError(f"--measured-from {source}: {type(exc).__name__}: {exc}") from None
        for obj in records if isinstance(records, list) else []:
            try:
                values.append(LatencyRecord.from_obj(obj).latency_ms)
            except RecordError:
                continue
    else:
        try:
            points = load_points(Path(source))
        except (OSError, ExportError, ValueError) as exc:
            raise CompareError(f"--measured-from {source}: {exc}") from None
        values = [p.latencyMs for p in points if p.latencyMs is not None]
    if not values:
        raise CompareError(f"--measured-from {source}: no latencies there to take p50 and p95 of")
    return [max(0.0, percentile(values, q)) for q in (0.5, 0.95)]


def latencies_of(text: str | None, measured_from: str = DEFAULT_TRACKER) -> list[float] | None:
    """``--latency 0,50,100`` -> [0.0, 50.0, 100.0] ms; ``measured`` -> [p50, p95]; None when not given."""
    if text is None:
        return None
    if text.strip() == "measured":
        return measured_latencies(measured_from)
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise CompareError(f"--latency: give milliseconds, e.g. 0,50,100 (got {text!r})") from None
    if not values or any(not math.isfinite(v) or v < 0 for v in values):
        raise CompareError(f"--latency: give milliseconds >= 0, e.g. 0,50,100 (got {text!r})")
    return values


HEAD = (
    "rank", "algorithm", "done", "time s", "avg e_xt m", "p95 e_xt m", "max e_xt m", "path/ref",
    "|dω/dt| rad/s²", "jerk v m²/s⁵", "jerk ω rad²/s⁵", "path m", "avg e_d m", "final m",
)  # fmt: skip


def _jerk(value: float | None) -> str:
    return "—" if value is None else f"{value:.1f}"


def table(results: list[RunResult]) -> str:
    """One ranked block per mission, then the overall answer and the rule."""
    answer = ranking_of(results)
    groups = ranking.by_mission(results)
    rows: list[list[str]] = []
    for m in answer.missions:
        rows.append([m.mission])
        rows.append(list(HEAD))
        # avg e_xt (what the ranking orders by) to as many decimals as tell the ranked runs apart
        d = TR.decimals([TR.Figure(r.tracking.xte_mean_m, 0.0) for r in groups[m.mission]])
        for i, r in enumerate(groups[m.mission], 1):
            mark = " *" if i == 1 and r.completed else ""
            t = r.tracking
            rows.append([
                f"{i}{mark}", r.algorithm, "yes" if r.completed else "NO", f"{r.time_s:.1f}",
                f"{t.xte_mean_m:.{d}f}", f"{t.xte_p95_m:.3f}", f"{t.xte_max_m:.3f}", _ratio(t.path_ratio),
                f"{t.mean_abs_dw_dt:.2f}", _jerk(t.linear_jerk), _jerk(t.angular_jerk),
                f"{r.stats.totalPathLength:.2f}", f"{r.stats.avgDistanceError:.3f}", f"{r.final_error_m:.3f}",
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


def _ratio(value: float | None) -> str:
    return "—" if value is None else f"{value:.2f}"


def _aligned(rows: list[list[str]], left: int = 2) -> list[str]:
    widths = [max(len(row[c]) for row in rows) for c in range(len(rows[0]))]
    out = []
    for row in rows:
        cells = enumerate(zip(row, widths, strict=True))
        out.append("  ".join(v.ljust(w) if c < left else v.rjust(w) for c, (v, w) in cells))
    return out


def export(results: list[RunResult], directory: Path, stem: str | None = None) -> list[Path]:
    """One comparison's points and run summaries as CSV, JSON and MCAP, ``stem.csv`` etc. (default
    ``arbiter_compare_<epoch ms>``)."""
    points = [p for r in results for p in r.points]
    runs = [r.summary for r in results if r.summary is not None]
    rows = [row_of(r) for r in runs]  # one run per (mission, algorithm)
    stats = stats_of_points(points)
    stem = stem or f"arbiter_compare_{time.time_ns() // 1_000_000}"
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
    speed, note = cap_setting("speed", args.speed, DEFAULT_LIMITS.max_linear, "m/s")
    turn, note_turn = cap_setting("turn", args.turn, DEFAULT_LIMITS.max_angular, "rad/s")
    for line in (note, note_turn):
        if line:
            print(f"arbiter-tui compare: {line}", file=sys.stderr)
    try:
        latencies = latencies_of(args.latency, args.measured_from)
        links = [
            LinkModel(ms / 1e3, args.jitter / 1e3, args.loss, args.odom_delay / 1e3)
            for ms in (latencies if latencies is not None else [0.0])
        ]
    except (CompareError, LinkModelError) as exc:
        print(f"arbiter-tui compare: {exc}", file=sys.stderr)
        return 2
    if args.plot is not None:
        from .plotfile import cannot_plot

        if (why := cannot_plot(args.plot)) is not None:  # before the sweep, not after its minutes
            print(f"arbiter-tui compare: --plot {args.plot}: {why}", file=sys.stderr)
            return 2
    if latencies is not None or not links[0].perfect or args.trials > 1 or args.plot is not None:
        setup = Sweep(missions, algorithms, speed, turn, links, args.seed, args.trials, args.cmd_timeout)
        return sweep(setup, args.json, args.plot, args.export_dir)
    results = compare(missions, algorithms, speed, turn, cmd_timeout=args.cmd_timeout)
    written: list[Path] = []
    if args.export_dir is not None:
        try:
            written = export(results, args.export_dir)
        except ExportError as exc:
            print(f"arbiter-tui compare: {exc}", file=sys.stderr)
            return 1
    if args.json:
        print(json.dumps(body_of(results, written), allow_nan=False))
    else:
        print(table(results))
        for path in written:
            print(f"wrote {path}")
    return 0


@dataclass(frozen=True)
class Sweep:
    missions: list[str]
    algorithms: list[str]
    speed: float
    turn: float
    links: list[LinkModel]
    seed: int = 0
    trials: int = 1
    cmd_timeout: float = CMD_TIMEOUT_S


TRIAL_SEED_STEP = 10_000  # trial k draws from seed + k x this (+ the run's index within the comparison)


@dataclass(frozen=True)
class SweepCell:
    link: LinkModel
    runs: list[list[RunResult]]  # runs[k]: trial k, every algorithm on every mission
    summaries: list[TR.CellSummary]
    verdicts: list[TR.Verdict]

    def as_dict(self) -> dict[str, Any]:
        return {
            "link": self.link.as_dict(),
            "runs": [{"trial": k, **r.as_dict()} for k, trial in enumerate(self.runs) for r in trial],
            "missions": [v.as_dict() for v in self.verdicts],
            "overall": ranking.rank(self.summaries).overall.as_dict(),
        }


def run_sweep(setup: Sweep) -> list[SweepCell]:
    """Every link x trial x mission x algorithm, in simulated time; deterministic for a seed."""
    out = []
    for link in setup.links:
        runs = [
            compare(
                setup.missions,
                setup.algorithms,
                setup.speed,
                setup.turn,
                t0_ms=0.0,
                link_model=link,
                seed=setup.seed + k * TRIAL_SEED_STEP,
                cmd_timeout=setup.cmd_timeout,
            )
            for k in range(setup.trials)
        ]
        summaries = TR.cells(runs)
        out.append(SweepCell(link, runs, summaries, TR.verdicts(summaries)))
    return out


def sweep_body(setup: Sweep, cells: list[SweepCell], written: list[Path] | None = None) -> dict[str, Any]:
    """The sweep's JSON (schema: tests/unit/test_compare.py, README); ``exports``: the files written."""
    return {
        "sweep": [c.as_dict() for c in cells],
        "trials": setup.trials,
        "seed": setup.seed,
        "cmd_timeout_s": setup.cmd_timeout,
        "jitter": "half-normal: each command's delay is latency + |N(0, jitter)|, delivered in order",
        "interval": INTERVAL,
        "rule": ranking.RULE,
        "verdict_rule": VERDICT_RULE,
        "exports": [str(p) for p in written or ()],
    }


def _from(results: list[RunResult], t0_ms: float) -> list[RunResult]:
    """A comparison run in simulated time from 0 (a sweep's, deterministic), moved to start at
    ``t0_ms``, as plain ``compare`` runs from now: its points and summaries, each run's span kept."""

    def later(ms: float | None) -> float | None:
        return None if ms is None else ms + t0_ms

    out = []
    for r in results:
        s = r.summary
        if s is not None:
            s = replace(s, start_ms=s.start_ms + t0_ms, end_ms=later(s.end_ms), last_ms=later(s.last_ms))
        points = [replace(p, timestamp=p.timestamp + t0_ms) for p in r.points]
        out.append(replace(r, points=points, summary=s))
    return out


def export_sweep(cells: list[SweepCell], directory: Path) -> list[Path]:
    """Every comparison of a sweep, one per link and trial, as plain ``--export-dir`` writes one:
    ``arbiter_compare_<epoch ms>_latency<MS>ms_trial<K>`` .csv, .json and .mcap (the name carries the
    link's latency, the one figure a sweep varies; each file's runs are numbered from 1)."""
    now = time.time_ns() // 1_000_000
    written: list[Path] = []
    for cell in cells:
        for k, results in enumerate(cell.runs):
            stem = f"arbiter_compare_{now}_latency{cell.link.latency_s * 1e3:g}ms_trial{k}"
            written += export(_from(results, now), directory, stem)
    return written


def sweep(setup: Sweep, as_json: bool, plot: Path | None = None, export_dir: Path | None = None) -> int:
    """The whole comparison once per link (one per ``--latency`` value) and trial; per mission a ranked
    table with intervals and a verdict, then avg e_xt per controller and latency side by side. With
    ``export_dir``, every comparison's runs written there (``export_sweep``)."""
    cells = run_sweep(setup)
    if plot is not None:
        try:
            from .plotfile import write_plot

            write_plot(plot, cells)
        except (OSError, ImportError) as exc:  # checked before the sweep; a disk that filled since
            print(f"arbiter-tui compare: --plot {plot}: {exc}", file=sys.stderr)
            return 1
    written: list[Path] = []
    if export_dir is not None:
        try:
            written = export_sweep(cells, export_dir)
        except ExportError as exc:
            print(f"arbiter-tui compare: {exc}", file=sys.stderr)
            return 1
    if as_json:
        print(json.dumps(sweep_body(setup, cells, written), allow_nan=False))
        return 0
    for cell in cells:
        d = cell.link.as_dict()
        print(
            f"== latency {d['latency_ms']:g} ms, jitter {d['jitter_ms']:g} ms, loss {d['loss']:g}, "
            f"odometry delay {d['odom_delay_ms']:g} ms; {setup.trials} trial(s)"
        )
        print(trial_table(cell.verdicts))
        print()
    print(f"avg e_xt (m) by one-way latency ({INTERVAL if setup.trials > 1 else 'one trial'}):")
    print("\n".join(error_vs_latency(cells)))
    for path in ([plot] if plot is not None else []) + written:
        print(f"wrote {path}")
    return 0


TRIAL_HEAD = ("rank", "algorithm", "done", "avg e_xt m", "p95 e_xt m", "time s", "|dω/dt|", "avg e_d m")


def trial_table(verdicts: list[TR.Verdict]) -> str:
    """Per mission its ranking; every cell of a column in one form (``mean±ci95`` when the figures are
    over several trials), avg e_xt to as many decimals as the ranking and the verdict need to be seen."""
    lines = []
    for v in verdicts:
        lines.append(v.mission)
        several = v.ranking[0].trials > 1
        digits = TR.decimals([c.figures["xte_mean_m"] for c in v.ranking], verdict=v)
        rows = [list(TRIAL_HEAD)]
        for i, c in enumerate(v.ranking, 1):
            f = c.figures
            rows.append([
                f"{i}{' *' if c.algorithm == v.best else ''}", c.algorithm, f"{c.completions}/{c.trials}",
                f["xte_mean_m"].text(digits, several), f["xte_p95_m"].text(3, several),
                f["time_s"].text(1, several), f["mean_abs_dw_dt"].text(2, several),
                f["avgDistanceError"].text(3, several),
            ])  # fmt: skip
        lines.extend("  " + line.rstrip() for line in _aligned(rows))
        lines.append(f"  verdict: {v.text(digits, several)}")
    lines.append(f"* {ranking.RULE_MISSION}; {VERDICT_RULE}")
    return "\n".join(lines)


def error_vs_latency(cells: list[SweepCell]) -> list[str]:
    """avg e_xt per controller (rows) and latency (columns); each mission's rows to the decimals its
    tables needed at any latency, every cell ``mean±ci95`` when the figures are over several trials."""
    several = len(cells[0].runs) > 1
    digits: dict[str, int] = {}
    for c in cells:
        for v in c.verdicts:
            d = TR.decimals([s.figures["xte_mean_m"] for s in v.ranking], verdict=v)
            digits[v.mission] = max(digits.get(v.mission, 3), d)
    head = ["mission", "algorithm", *(f"{c.link.latency_s * 1e3:g} ms" for c in cells)]
    rows = [head]
    for i, s in enumerate(cells[0].summaries):
        d = digits.get(s.mission, 3)
        rows.append([
            s.mission, s.algorithm, *(c.summaries[i].figures["xte_mean_m"].text(d, several) for c in cells)
        ])  # fmt: skip
    return _aligned(rows)


def body_of(results: list[RunResult], written: list[Path]) -> dict[str, Any]:
    """The JSON of one comparison: runs, per-mission rankings, the overall answer, the rule."""
    answer = ranking_of(results)
    groups = ranking.by_mission(results)
    return {
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
