"""``arbiter-tui stats FILE`` as a user runs it: a real subprocess on real files."""

import json
import os
import subprocess
import sys

import pytest

from arbiter_tui.analytics.exports import to_csv, to_json, to_mcap
from arbiter_tui.analytics.store import STATS_FIELDS, stats_of_points
from arbiter_tui.session.compare import AUTONOMOUS

from ..support.points import random_points

HEADER = b"timestamp,x,y,theta,linearVel,angularVel,distanceError,headingError,algorithm,latencyMs\n"


def run(*args):
    return subprocess.run(
        [sys.executable, "-m", "arbiter_tui.cli", "stats", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.mark.parametrize("fmt", ["csv", "json", "mcap"])
def test_stats_json_matches_the_store(tmp_path, fmt):
    pts = random_points(40, seed=9)
    f = tmp_path / f"export.{fmt}"
    if fmt == "mcap":  # the console's own MCAP export, read back by content
        f.write_bytes(to_mcap(pts))
    else:
        f.write_text(to_csv(pts) if fmt == "csv" else to_json(pts))
    r = run(f, "--json")
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    want = stats_of_points(pts).as_dict()
    assert list(got) == list(STATS_FIELDS)
    for k in want:
        assert got[k] == pytest.approx(want[k], rel=1e-12)


def test_stats_table_lists_nine_lines(tmp_path):
    f = tmp_path / "e.csv"
    f.write_text(to_csv(random_points(5)))
    r = run(f)
    assert r.returncode == 0
    lines = r.stdout.strip().splitlines()
    assert [ln.split()[0] for ln in lines] == list(STATS_FIELDS)
    assert lines[0].split()[1] == "5"


@pytest.mark.parametrize(
    "content",
    [
        b"",
        b"\x00\xff\xfe binary",
        b"hello,world\n1,2\n",
        b'{"dataPoints": [1]}',
        b"{oops",
        HEADER + b"1,nan,0,0,0,0,0,0,manual,\n",
        HEADER + b"1,1e999,0,0,0,0,0,0,manual,\n",
        HEADER + b"1,0,0\n",
        HEADER + b"1,0,0,0,0,0,0,0,manual,,extra\n",
        b'{"dataPoints": [{"timestamp": "x"}]}',
        b'{"dataPoints": [{"timestamp": 1, "x": NaN}]}',
        b'{"a":' * 100_000,
        b"[1, 2]",
    ],
    ids=lambda content: repr(content[:24]),
)
def test_bad_files_get_one_line_errors(tmp_path, content):
    f = tmp_path / "bad"
    f.write_bytes(content)
    r = run(f)
    assert r.returncode == 1
    assert "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert r.stderr.startswith("arbiter-tui stats: ")


def test_missing_file_directory_and_fifo(tmp_path):
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)  # reading it would block forever
    for target in (tmp_path / "missing.csv", tmp_path, fifo):
        r = run(target)
        assert r.returncode == 1
        assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_a_bad_flag_is_one_line_on_stderr_from_the_real_entry_point():
    """The in-process cases are in tests/unit/test_cli_args.py; this one runs the installed module."""
    r = subprocess.run(
        [sys.executable, "-m", "arbiter_tui.cli", "--key-timeout", "0"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("arbiter-tui"), r.stderr


def test_a_broken_mcap_is_one_line(tmp_path):
    good = to_mcap(random_points(30))
    f = tmp_path / "cut.mcap"
    f.write_bytes(good[: len(good) // 2])  # truncated mid-file
    r = run(f)
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "MCAP" in r.stderr


def test_by_algorithm_matches_the_analytics_screens_grouping(tmp_path):
    from arbiter_tui.analytics.store import AnalyticsStore

    pts = random_points(90, seed=3)
    f = tmp_path / "e.json"
    f.write_text(to_json(pts))
    r = run(f, "--by", "algorithm", "--json")
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    store = AnalyticsStore(max_data_points=1000)
    store.start_collection()
    for p in pts:
        store.record(p)
    want = {k: v.as_dict() for k, v in store.stats_by_algorithm().items()}
    assert set(got) == set(want) == {p.algorithm for p in pts}
    for algo in want:
        for k in STATS_FIELDS:
            assert got[algo][k] == pytest.approx(want[algo][k], rel=1e-12)
    table = run(f, "--by", "algorithm").stdout.splitlines()
    assert [line for line in table if line.startswith("[")] == [f"[{a}]" for a in want]


def test_by_run_reads_every_format_of_a_compare_export(tmp_path):
    """`compare --export-dir` writes runs; `stats --by run` on each file gives each run's stats back."""
    r = subprocess.run(
        [sys.executable, "-m", "arbiter_tui.cli", "compare", "--mission", "square", "--json",
         "--export-dir", str(tmp_path)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    body = json.loads(r.stdout)
    want = {f"run {run['run']}": run["stats"] for run in body["runs"]}
    assert len(want) == len(AUTONOMOUS)  # one run per controller on the one mission
    for path in body["exports"]:
        got = run(path, "--by", "run", "--json")
        assert got.returncode == 0, got.stderr
        stats = json.loads(got.stdout)
        assert set(stats) == set(want), path
        for name, expected in want.items():
            for k in STATS_FIELDS:
                assert stats[name][k] == pytest.approx(expected[k], rel=1e-9), (path, name, k)
    table = run(body["exports"][0], "--by", "run").stdout.splitlines()
    assert sorted(line for line in table if line.startswith("[")) == sorted(f"[{name}]" for name in want)
