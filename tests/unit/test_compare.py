"""`arbiter-tui compare`: every algorithm on every mission in simulated time, ranked by a stated rule."""

import json
import time

import pytest

from arbiter_core.controllers import MISSIONS
from arbiter_tui.analytics.files import load_points
from arbiter_tui.analytics.ranking import RULE, RULE_MISSION, RULE_OVERALL
from arbiter_tui.analytics.store import STATS_FIELDS
from arbiter_tui.analytics.tracking import TRACKING_FIELDS
from arbiter_tui.cli import main
from arbiter_tui.session.compare import AUTONOMOUS, run_one


def run_json(capsys, *args):
    assert main(["compare", "--json", *args]) == 0
    return json.loads(capsys.readouterr().out)


RUN_KEYS = {
    "run",  # the runId its exported points carry
    "algorithm",
    "mission",
    "completed",
    "time_s",
    "final_error_m",
    "max_linear_vel",
    "stats",
    "tracking",
}


def test_json_schema_ranking_and_best(capsys):
    started = time.monotonic()
    body = run_json(capsys)
    wall = time.monotonic() - started
    runs = body["runs"]
    assert {(r["algorithm"], r["mission"]) for r in runs} == {(a, m) for a in AUTONOMOUS for m in MISSIONS}
    for r in runs:
        assert set(r) == RUN_KEYS
        assert tuple(r["stats"]) == STATS_FIELDS and r["completed"] and r["final_error_m"] <= 0.15
        assert set(r["tracking"]) == {"samples", *TRACKING_FIELDS}
        assert r["tracking"]["time_to_complete_s"] == r["time_s"]  # completed: its time
    assert sorted(r["run"] for r in runs) == list(range(1, len(MISSIONS) * len(AUTONOMOUS) + 1))
    assert [m["mission"] for m in body["missions"]] == list(MISSIONS)
    for m in body["missions"]:  # ranked within each mission, never across, by mean cross-track error
        ranked = m["ranking"]
        assert {r["mission"] for r in ranked} == {m["mission"]}
        assert [r["rank"] for r in ranked] == list(range(1, len(AUTONOMOUS) + 1))
        errors = [r["tracking"]["xte_mean_m"] for r in ranked]
        assert errors == sorted(errors) and m["best"] == ranked[0]["algorithm"] and m["not_run"] == []
    overall = body["overall"]
    assert overall["missions"] == list(MISSIONS) and overall["rule"] == RULE_OVERALL
    assert body["best"] == {"algorithm": overall["best"]}
    assert overall["mean_rank"][overall["best"]] == min(overall["mean_rank"].values())
    assert body["rule"] == RULE
    # simulated time: minutes of driving in (much) less wall time
    assert sum(r["time_s"] for r in runs) > 10 * wall


def test_the_speed_cap_holds_for_every_sample(capsys):
    body = run_json(capsys, "--mission", "figure_eight", "--speed", "0.1", "--turn", "0.3")
    for r in body["runs"]:
        assert r["completed"] and r["max_linear_vel"] <= 0.1 and r["stats"]["maxLinearVel"] <= 0.1
    result = run_one("pure_pursuit", "figure_eight", speed=0.1, turn=0.3)
    assert all(abs(p.linearVel) <= 0.1 + 1e-12 and abs(p.angularVel) <= 0.3 + 1e-12 for p in result.points)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--mission", "circle"], "unknown 'circle'; choose from square, figure_eight, slalom, corner"),
        (["--trials", "0"], "--trials"),
        (["--plot", "out.pdf"], "give a .svg or .png file"),
        (["--algorithms", "go_to_goal,manual"], "unknown 'manual'; choose from go_to_goal, pure_pursuit, st"),
        (["--mission", ","], "give at least one of"),
        (["--speed", "0"], "must be a positive finite number"),
        (["--latency", "0,fast"], "--latency: give milliseconds"),
        (["--latency", "-5"], "--latency: give milliseconds >= 0"),
        (["--loss", "1"], "loss must be below 1"),
    ],
)
def test_bad_names_are_one_line_errors(capsys, args, words):
    code = None
    try:
        code = main(["compare", *args])
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0], err


def test_export_dir_writes_the_runs_data(tmp_path, capsys):
    body = run_json(capsys, "--mission", "square", "--export-dir", str(tmp_path))
    paths = sorted(body["exports"])
    assert [p.rsplit(".", 1)[1] for p in paths] == ["csv", "json", "mcap"]
    total = sum(r["stats"]["sampleCount"] for r in body["runs"])
    for p in paths[:2]:  # CSV and JSON read back with the same reader `stats` uses
        points = load_points(tmp_path / p.rsplit("/", 1)[1])
        assert len(points) == total and {q.algorithm for q in points} == set(AUTONOMOUS)


def test_the_table_names_the_best_and_the_rule(capsys):
    assert main(["compare", "--mission", "square"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "square" and out[1].split()[:3] == ["rank", "algorithm", "done"]
    assert out[2].strip().startswith("1 *") and out[-2] == f"* {RULE_MISSION}"
    assert out[-1].startswith(f"{RULE_OVERALL}: ") and "mean rank 1 over square" in out[-1]


FIGURE_KEYS = {"mean", "ci95"}


def test_a_sweeps_json_holds_every_cell_trial_and_the_rules(capsys):
    """The sweep's JSON schema: per link every trial's runs, per mission the ranking with mean ± 95 %
    interval and a verdict, the overall answer; the rules and the seed; deterministic for a seed."""
    args = ["--latency", "0,300", "--jitter", "10", "--odom-delay", "20", "--seed", "4", "--trials", "3",
            "--mission", "square,corner"]  # fmt: skip
    body = run_json(capsys, *args)
    assert set(body) == {
        "sweep",
        "trials",
        "seed",
        "cmd_timeout_s",
        "jitter",
        "interval",
        "rule",
        "verdict_rule",
        "exports",
    }
    assert body["trials"] == 3 and body["seed"] == 4 and body["cmd_timeout_s"] == 0.5
    assert "half-normal" in body["jitter"] and "95 %" in body["interval"] and body["rule"] == RULE
    assert [cell["link"] for cell in body["sweep"]] == [
        {"latency_ms": ms, "jitter_ms": 10.0, "loss": 0.0, "odom_delay_ms": 20.0} for ms in (0.0, 300.0)
    ]
    for cell in body["sweep"]:
        assert set(cell) == {"link", "runs", "missions", "overall"}
        assert len(cell["runs"]) == 3 * 2 * len(AUTONOMOUS)
        assert all(set(r) == RUN_KEYS | {"trial"} for r in cell["runs"])
        assert {r["trial"] for r in cell["runs"]} == {0, 1, 2}
        for m in cell["missions"]:
            assert set(m) == {"mission", "best", "clear", "overlapping", "reason", "ranking"}
            assert m["clear"] == (m["best"] is not None) and m["reason"]
            ranked = m["ranking"]
            assert [r["rank"] for r in ranked] == list(range(1, len(AUTONOMOUS) + 1))
            for r in ranked:
                assert {"algorithm", "mission", "trials", "completed", "xte_mean_m", "time_s"} <= set(r)
                assert set(r["xte_mean_m"]) == FIGURE_KEYS and r["trials"] == 3
            means = [r["xte_mean_m"]["mean"] for r in ranked]
            assert means == sorted(means)
            # the mean is the mean of the trials' runs
            runs = [
                r
                for r in cell["runs"]
                if (r["mission"], r["algorithm"]) == (m["mission"], ranked[0]["algorithm"])
            ]
            assert ranked[0]["xte_mean_m"]["mean"] == pytest.approx(
                sum(r["tracking"]["xte_mean_m"] for r in runs) / 3, abs=1e-6
            )
    assert body == run_json(capsys, *args)  # deterministic for a seed


def test_trials_draw_different_jitter_and_the_interval_says_so(capsys):
    body = run_json(capsys, "--latency", "200", "--jitter", "40", "--trials", "4", "--mission", "square")
    (cell,) = body["sweep"]
    errors = {r["tracking"]["xte_mean_m"] for r in cell["runs"] if r["algorithm"] == "pure_pursuit"}
    assert len(errors) == 4  # each trial its own draws
    (m,) = cell["missions"]
    assert all(r["xte_mean_m"]["ci95"] > 0 for r in m["ranking"])
    # no jitter, no loss: the trials are the same run and the interval has no width
    body = run_json(capsys, "--latency", "200", "--trials", "3", "--mission", "square")
    assert all(r["xte_mean_m"]["ci95"] == 0 for r in body["sweep"][0]["missions"][0]["ranking"])


def test_a_sweep_prints_a_table_per_latency_and_the_errors_side_by_side(capsys):
    assert main(["compare", "--latency", "0,200", "--mission", "square"]) == 0
    out = capsys.readouterr().out
    assert out.count("== latency") == 2 and "== latency 200 ms, jitter 0 ms" in out
    last = out.strip().splitlines()[-1 - len(AUTONOMOUS) :]
    assert last[0].split() == ["mission", "algorithm", "0", "ms", "200", "ms"]
    assert out.count("verdict: ") == 2
    assert {line.split()[1] for line in last[1:]} == set(AUTONOMOUS)


def test_latency_measured_takes_p50_and_p95_of_an_exports_latencies(tmp_path, capsys):
    """The sweep starts from the user's real link: the p50 and p95 of the latencies an analytics export
    carries (negative ones, clocks apart, count as 0: a modelled link is never early)."""
    from dataclasses import replace

    from arbiter_core.stats import percentile
    from arbiter_tui.analytics.exports import to_csv

    base = run_one("go_to_goal", "square").points[:100]
    latencies = [-1.0, *(float(i) for i in range(1, 99)), None]  # 98 measured, one negative, one unknown
    points = [replace(p, latencyMs=lat) for p, lat in zip(base, latencies, strict=True)]
    export = tmp_path / "arbiter_analytics_x.csv"
    export.write_text(to_csv(points))
    body = run_json(capsys, "--latency", "measured", "--measured-from", str(export), "--mission", "square")
    measured = [lat for lat in latencies if lat is not None]
    want = [max(0.0, percentile(measured, q)) for q in (0.5, 0.95)]
    assert [cell["link"]["latency_ms"] for cell in body["sweep"]] == pytest.approx(want)
    empty = tmp_path / "no_latency.csv"
    empty.write_text(to_csv(base))  # client-side simulation: no latency known
    assert main(["compare", "--latency", "measured", "--measured-from", str(empty)]) == 2
    assert "no latencies there" in capsys.readouterr().err


@pytest.mark.parametrize("suffix", ["svg", "png"])
def test_plot_writes_the_error_vs_latency_figure(tmp_path, capsys, suffix):
    out = tmp_path / f"sweep.{suffix}"
    assert main(["compare", "--latency", "0,200", "--mission", "corner", "--plot", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    data = out.read_bytes()
    if suffix == "svg":
        text = data.decode()
        assert text.lstrip().startswith("<?xml") and "<svg" in text
        assert "corner" in text and "one-way command latency" in text  # the panel and its axis
    else:
        assert data.startswith(b"\x89PNG\r\n\x1a\n") and len(data) > 10_000


def _cell(algorithm: str, xte: float, ci95: float, trials: int = 3):
    """A controller's summary on figure_eight over ``trials`` trials with avg e_xt ``xte ± ci95``."""
    from dataclasses import replace

    from arbiter_tui.session import trials as TR

    base = TR.summarize([run_one(algorithm, "figure_eight")] * trials)
    figures = {**base.figures, "xte_mean_m": TR.Figure(xte, ci95)}
    return replace(base, figures=figures, tracking=replace(base.tracking, xte_mean_m=xte))


def _xte_cells(table: str) -> dict[str, str]:
    """algorithm -> its avg e_xt cell, from a trial table of one mission."""
    lines = table.splitlines()
    col = lines[1].split().index("avg")  # "rank algorithm done avg e_xt m ..."
    rows = [line.replace(" * ", " ").split() for line in lines[2:]]
    return {row[1]: row[col] for row in rows if row[0].isdigit()}


def _interval(cell: str) -> tuple[float, float]:
    mean, ci = (float(v) for v in cell.split("±"))
    return mean - ci, mean + ci


def test_a_trial_tables_column_has_one_form_and_the_digits_the_verdict_needs():
    """Issue 31: figure_eight at 0 ms printed stanley `0.016±0.000` (an interval of 1e-18, rounding noise)
    beside go_to_goal `0.016` under the verdict "stanley, apart from every other". Every cell of a column
    now has the same form, and avg e_xt has as many decimals as tell the ranked means apart."""
    from arbiter_tui.commands.compare import trial_table
    from arbiter_tui.session import trials as TR

    summaries = [
        _cell("stanley", 0.015611, 1e-18),
        _cell("go_to_goal", 0.016049, 0.0),
        _cell("pure_pursuit", 0.026231, 0.0),
    ]
    (v,) = TR.verdicts(summaries)
    assert v.best == "stanley"
    cells = _xte_cells(trial_table([v]))
    assert all("±" in c for c in cells.values()), cells  # one form: every cell with its interval
    assert len({c.split("±")[0] for c in cells.values()}) == 3, cells  # the ranked means differ visibly
    assert cells["stanley"] in trial_table([v]).splitlines()[-2]  # the verdict quotes the cell as printed
    # --json keeps its reason as it was
    assert v.reason == "stanley (avg e_xt 0.016±0.000 m, apart from every other)"
    # one trial: no interval in any cell
    (one,) = TR.verdicts([_cell("stanley", 0.015611, 0.0, 1), _cell("go_to_goal", 0.016049, 0.0, 1)])
    assert all("±" not in c for c in _xte_cells(trial_table([one])).values())


@pytest.mark.parametrize(
    ("best", "rival"),
    [
        ((0.0104, 0.0003), (0.0110, 0.0004)),  # overlapping, though 3 decimals print 0.010 and 0.011 apart
        ((0.0104, 0.0002), (0.0108, 0.0001)),  # apart by 0.0001
        ((0.015611, 1e-18), (0.016049, 0.0)),  # apart, equal at 3 decimals
    ],
)
def test_the_printed_intervals_overlap_exactly_when_the_verdict_says_so(best, rival):
    from arbiter_tui.commands.compare import trial_table
    from arbiter_tui.session import trials as TR

    (v,) = TR.verdicts([_cell("stanley", *best), _cell("go_to_goal", *rival)])
    cells = _xte_cells(trial_table([v]))
    low, _ = _interval(cells["go_to_goal"])
    _, high = _interval(cells["stanley"])
    assert (low <= high) == (v.best is None), (cells, v.reason)


def test_the_single_comparisons_table_tells_close_runs_apart():
    from dataclasses import replace

    from arbiter_tui.commands.compare import table

    runs = [run_one(a, "figure_eight") for a in ("stanley", "go_to_goal")]
    xte = (0.015611, 0.016049)
    runs = [replace(r, tracking=replace(r.tracking, xte_mean_m=v)) for r, v in zip(runs, xte, strict=True)]
    lines = table(runs).splitlines()
    head = lines[1].split()
    col = head.index("avg") - 1  # "time s" is two words
    means = [line.replace(" * ", " ").split()[col] for line in lines[2:4]]
    assert means[0] != means[1], lines[:4]


def test_the_sweeps_last_table_has_one_form_per_column(capsys):
    assert main(["compare", "--latency", "0,100", "--trials", "3", "--mission", "figure_eight"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    rows = out[-len(AUTONOMOUS) :]
    assert all(cell.count("±") == 1 for row in rows for cell in row.split()[2:]), rows


def test_the_plots_legend_is_off_the_data_and_in_the_image(tmp_path, monkeypatch):
    """Issue 31: the legend sat inside a panel, over the 300 ms points. Now no legend overlaps any panel's
    axes, and the saved image holds the legend."""
    from matplotlib.figure import Figure

    from arbiter_core.linkmodel import LinkModel
    from arbiter_tui.commands.compare import Sweep, run_sweep
    from arbiter_tui.commands.plotfile import write_plot

    seen = []
    original = Figure.savefig

    def savefig(fig, *args, **kwargs):  # what the saved figure holds, as it was drawn
        out = original(fig, *args, **kwargs)
        renderer = fig.canvas.get_renderer()
        panels = [ax.get_window_extent(renderer) for ax in fig.axes if ax.get_visible()]
        legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend() is not None)]
        seen.append((fig.bbox, panels, [lg.get_window_extent(renderer) for lg in legends], kwargs))
        return out

    monkeypatch.setattr(Figure, "savefig", savefig)
    links = [LinkModel(0.0), LinkModel(0.3)]
    cells = run_sweep(Sweep(["corner", "square", "slalom"], list(AUTONOMOUS), 0.5, 1.0, links))
    write_plot(tmp_path / "sweep.png", cells)
    ((page, panels, legends, kwargs),) = seen
    assert len(panels) == 3 and legends
    for box in legends:
        assert not any(box.overlaps(panel) for panel in panels), (box, panels)
        # in the image: the figure's own area, unless the image is cut to what it draws
        assert kwargs.get("bbox_inches") == "tight" or page.contains(box.x1, box.y1)


def test_plot_without_matplotlib_says_how_to_install_it_from_pypi_and_a_clone(tmp_path, capsys, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib -> ImportError
    out = tmp_path / "sweep.svg"
    assert main(["compare", "--latency", "0", "--mission", "corner", "--plot", str(out)]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert "pip install 'arbiter-tui[report]'" in err and "pip install -e '.[report]'" in err, err
    assert not out.exists()


@pytest.mark.parametrize(
    ("where", "says"),
    [
        ("no-matplotlib", "needs matplotlib: pip install"),
        ("/proc/sweep.svg", "/proc: not writable"),
        ("missing/sweep.svg", "no such directory: "),
        ("a-dir.svg", "a directory, not a file"),
    ],
)
def test_a_plot_that_cannot_be_written_is_refused_before_the_sweep(
    tmp_path, capsys, monkeypatch, where, says
):
    """Issue 46: a 20 s sweep ended in "needs matplotlib" or a plot path that takes no file. Now that is
    one line on stderr and exit 2 before anything runs: no sweep, no tables, no file."""
    import sys

    from arbiter_tui.commands import compare as compare_cmd

    def sweep_ran(*args, **kwargs):
        raise AssertionError("the sweep ran before the plot was known to be writable")

    monkeypatch.setattr(compare_cmd, "run_sweep", sweep_ran)
    monkeypatch.chdir(tmp_path)
    if where == "no-matplotlib":
        monkeypatch.setitem(sys.modules, "matplotlib", None)
        where = "sweep.svg"
    if where == "a-dir.svg":
        (tmp_path / where).mkdir()
    assert main(["compare", "--latency", "0,100", "--mission", "corner", "--plot", where]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1, err
    assert err.startswith(f"arbiter-tui compare: --plot {where}: ") and says in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == (["a-dir.svg"] if where == "a-dir.svg" else [])


def test_a_sweep_exports_every_comparison_it_ran(tmp_path, capsys):
    """Issue 46: `compare --latency ... --export-dir DIR` wrote nothing and exited 0. Each link and trial
    is one comparison, written as plain `--export-dir` writes one, named by its latency and trial, its
    runs from now (the sweep runs them from 0 in simulated time)."""
    t0_ms = time.time() * 1000
    body = run_json(
        capsys, "--latency", "0,150", "--trials", "2", "--mission", "corner",
        "--algorithms", "stanley,pure_pursuit", "--export-dir", str(tmp_path),
    )  # fmt: skip
    stem = body["exports"][0].rsplit("/", 1)[1].split("_latency")[0]
    wanted = [
        f"{stem}_latency{ms}ms_trial{k}.{ext}"
        for ms in (0, 150)
        for k in (0, 1)
        for ext in ("csv", "json", "mcap")
    ]
    assert sorted(p.rsplit("/", 1)[1] for p in body["exports"]) == sorted(wanted)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(wanted)
    for cell, ms in zip(body["sweep"], (0, 150), strict=True):
        for k in (0, 1):
            runs = [r for r in cell["runs"] if r["trial"] == k]
            for ext in ("csv", "json"):  # read back with the reader `stats` uses
                points = load_points(tmp_path / f"{stem}_latency{ms}ms_trial{k}.{ext}")
                for r in runs:
                    mine = [p for p in points if p.runId == r["run"]]
                    assert len(mine) == r["stats"]["sampleCount"] and {p.algorithm for p in mine} == {
                        r["algorithm"]
                    }
                assert min(p.timestamp for p in points) >= t0_ms - 1000  # from now, not from 1970


def _compare_exit(capsys, *args):
    try:
        code = main(["compare", "--mission", "corner", "--algorithms", "stanley", *args])
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err.strip().splitlines()


@pytest.mark.parametrize("target", ["proc", "file", "read-only", "missing"])
def test_an_export_dir_that_takes_no_files_is_one_line(tmp_path, capsys, target):
    """Issue 31: `compare --export-dir /proc/1` ended in a FileNotFoundError traceback. A directory this
    user cannot write to, a file, or nothing at all: one line on stderr and exit 2, before running."""
    import os

    where = {"proc": "/proc/1", "file": tmp_path / "f", "read-only": tmp_path / "ro"}
    directory = where.get(target, tmp_path / "missing")
    if target == "file":
        directory.write_text("")
    if target == "read-only":
        directory.mkdir(mode=0o555)
    if target in ("proc", "read-only") and (not os.path.isdir(directory) or os.access(directory, os.W_OK)):
        pytest.skip(f"{directory} is writable here (root)")
    code, err = _compare_exit(capsys, "--export-dir", str(directory))
    assert code == 2 and len(err) == 1 and err[0].startswith("arbiter-tui compare: "), err
    assert str(directory) in err[0]


def test_an_export_that_fails_while_writing_is_one_line(tmp_path, capsys, monkeypatch):
    """A directory that passed the check but takes no file when written (as /proc/1 does for root)."""
    import os

    from arbiter_tui.analytics import files

    def refuse(*args, **kwargs):
        raise FileNotFoundError(2, "No such file or directory")

    monkeypatch.setattr(files.tempfile, "mkstemp", refuse)
    code, err = _compare_exit(capsys, "--export-dir", str(tmp_path))
    assert code == 1 and err == [f"arbiter-tui compare: cannot write export to {tmp_path}: {os.strerror(2)}"]
    assert list(tmp_path.iterdir()) == []


def test_help_prints_and_names_every_option(capsys):
    """`compare --help` raised ValueError: the --trials help quoted the interval's "95 %" unescaped."""
    with pytest.raises(SystemExit) as exit_:
        main(["compare", "--help"])
    assert exit_.value.code == 0
    out = " ".join(capsys.readouterr().out.split())
    for flag in ("--export-dir", "--trials", "--plot", "--latency", "--seed"):
        assert flag in out, flag
    assert "95 % t-interval" in out
