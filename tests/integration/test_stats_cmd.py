"""``arbiter-tui stats FILE`` as a user runs it: a real subprocess on real files."""

import contextlib
import io
import json
import os
import subprocess
import sys

import pytest

from arbiter_tui.analytics.exports import to_csv, to_json, to_mcap
from arbiter_tui.analytics.store import STATS_FIELDS, stats_of_points
from arbiter_tui.session.compare import AUTONOMOUS

from ..support.bags import Recording, drive, write_bag
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
    # issue 31: it said "record has length 5480051801619705163 that exceeds limit"
    (line,) = r.stderr.strip().splitlines()
    assert line.startswith(f"arbiter-tui stats: {f}: truncated MCAP: ") and "length" not in line, line


def _foreign_mcap(topic: str) -> bytes:
    from mcap_ros2.writer import Writer

    buf = io.BytesIO()
    writer = Writer(buf)
    schema = writer.register_msgdef("std_msgs/msg/String", "string data")
    writer.write_message(topic, schema, {"data": "hi"}, log_time=1, publish_time=1)
    writer.finish()
    return buf.getvalue()


def _flipped(data: bytes, at: float) -> bytes:
    i = int(len(data) * at)
    return data[:i] + bytes(b ^ 0xFF for b in data[i : i + 16]) + data[i + 16 :]


GOOD_MCAP = to_mcap(random_points(30))
GOOD_CSV = to_csv(random_points(10)).encode()
GOOD_JSON = to_json(random_points(10)).encode()


@pytest.mark.parametrize(
    ("content", "says"),
    [
        (b"", "empty file"),
        (b" \n\n", "empty file: only blank lines"),
        (bytes(range(256)), "binary data (starts 00 01 02"),
        (b"\x1f\x8b\x08\x00" + bytes(40), "gzip-compressed data (gunzip it first), not a CSV, JSON or MCAP"),
        ("timestamp,x\n".encode("utf-16"), "UTF-16 text (save it as UTF-8)"),
        (b"hello world\n", "text, but not a CSV, JSON or MCAP export: its first line is 'hello world'"),
        (b"a,b,c\n1,2,3\n", "CSV, but not an arbiter analytics export: its header is 'a,b,c'"),
        (GOOD_CSV[:-40], "truncated CSV: its last line (11) stops after"),
        (HEADER + b"1,0,0\n2,0,0,0,0,0,0,0,manual,\n", "bad arbiter CSV export: line 2: expected 10 columns"),
        (HEADER + b"1,x,0,0,0,0,0,0,manual,\n", "bad arbiter CSV export: line 2: x is not a number"),
        (b"[]", "JSON, but not an arbiter analytics export: the top level is an empty list"),
        (b"42", "JSON, but not an arbiter analytics export: the top level is a number"),
        (b'{"foo": 1}', "JSON, but not an arbiter analytics export: no \"dataPoints\" (its keys: 'foo')"),
        (b"{}", 'JSON, but not an arbiter analytics export: no "dataPoints" (an empty object)'),
        (b'{"dataPoints": {}}', 'JSON, but not an arbiter analytics export: "dataPoints" is an object'),
        (GOOD_JSON[:200], "truncated JSON: it ends at line"),
        (b"{oops", "invalid JSON: "),
        (b'{"dataPoints": [{"timestamp": "x"}]}', "bad arbiter JSON export: dataPoints[0]: timestamp is not"),
        (GOOD_MCAP[:8], "truncated MCAP: 8 bytes and no end marker"),
        (GOOD_MCAP[:-1], f"truncated MCAP: {len(GOOD_MCAP) - 1} bytes"),
        (_flipped(GOOD_MCAP, 0.5), "corrupt MCAP: "),
        (
            _foreign_mcap("/chatter"),
            "MCAP, but neither an arbiter analytics export (no /arbiter/data_point channel) nor a ros2 bag "
            "with odometry on /odom (its topics: /chatter)",
        ),
        (
            _foreign_mcap("/arbiter/data_point"),
            "MCAP, but not an arbiter analytics export: its "
            "/arbiter/data_point messages have no field 'timestamp'",
        ),
    ],
    ids=lambda v: repr(v[:24]) if isinstance(v, bytes) else None,
)
def test_each_broken_input_says_what_the_file_is_and_what_is_wrong(tmp_path, capsys, content, says):
    """Issue 31: `[]` was called "not an arbiter analytics CSV", a cut MCAP printed the reader's record
    length. One line each, naming the kind of file and the fault; exit 1; never a traceback."""
    from arbiter_tui.cli import main

    f = tmp_path / "input"
    f.write_bytes(content)
    assert main(["stats", str(f)]) == 1
    captured = capsys.readouterr()
    (line,) = captured.err.strip().splitlines()
    assert line.startswith(f"arbiter-tui stats: {f}: {says}"), line
    assert captured.out == ""


def test_a_damaged_mcap_is_always_an_export_error():
    """Bytes flipped anywhere in an MCAP: the reader's many exceptions all become one kind of error."""
    import random

    from arbiter_tui.analytics.exports import ExportFormatError, read_mcap

    rng = random.Random(31)
    for _ in range(300):
        data = bytearray(GOOD_MCAP)
        for _ in range(rng.randint(1, 8)):
            data[rng.randrange(8, len(data) - 8)] = rng.randrange(256)
        with contextlib.suppress(ExportFormatError):  # anything else (struct.error, ...) fails the test
            read_mcap(bytes(data))


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
    runs = sorted(body["runs"], key=lambda r: r["run"])
    for path in body["exports"]:  # each run headed with its algorithm, and its mission where the file says
        on = {r["run"]: "" if path.endswith(".csv") else f" on {r['mission']}" for r in runs}
        table = run(path, "--by", "run").stdout.splitlines()
        assert [line for line in table if line.startswith("[")] == [
            f"[run {r['run']} {r['algorithm']}{on[r['run']]}]" for r in runs
        ], path


def _store_with_idle_samples():
    """Samples outside every run first and between runs (as the console records them), then two runs."""
    from dataclasses import replace

    from arbiter_tui.analytics.store import AnalyticsStore

    from ..support.points import make_point

    store = AnalyticsStore()
    store.start_collection()
    t = 0

    def record(algorithm, n, run_id=None):
        nonlocal t
        for _ in range(n):
            t += 1
            store.record(replace(make_point(t, algorithm, run=run_id), linearVel=0.3))

    def ms():
        return 1_700_000_000_000.0 + 100.0 * t

    record("manual", 3)
    first = store.begin_run("pure_pursuit", "square", ms())
    record("pure_pursuit", 5, first)
    store.end_run("completed", ms(), 0.1)
    record("manual", 2)
    second = store.begin_run("stanley", "corner", ms())
    record("stanley", 4, second)
    store.end_run("aborted", ms(), 0.5)
    return store


def test_by_run_has_one_order_for_every_format_and_names_each_runs_algorithm(tmp_path, capsys):
    """Issue 31: `[no run]` came first from a CSV and last from JSON and MCAP, and a run was only its
    number. Now: runs in run order, `no run` last, each run with its algorithm (and mission where the file
    says: not in a CSV), in the text and in --json (added fields; the keys stay `run N`)."""
    from arbiter_tui.analytics.files import export_store
    from arbiter_tui.cli import main

    store = _store_with_idle_samples()
    for fmt in ("csv", "json", "mcap"):
        path = export_store(store, fmt, tmp_path, stem="e")
        assert main(["stats", str(path), "--by", "run"]) == 0
        headings = [line for line in capsys.readouterr().out.splitlines() if line.startswith("[")]
        on = ("", "") if fmt == "csv" else (" on square", " on corner")
        assert headings == [f"[run 1 pure_pursuit{on[0]}]", f"[run 2 stanley{on[1]}]", "[no run]"], fmt
        assert main(["stats", str(path), "--by", "run", "--json"]) == 0
        body = json.loads(capsys.readouterr().out)
        assert list(body) == ["run 1", "run 2", "no run"], fmt
        mission = (None, None) if fmt == "csv" else ("square", "corner")
        assert {k: (v.get("run"), v.get("algorithm"), v.get("mission")) for k, v in body.items()} == {
            "run 1": (1, "pure_pursuit", mission[0]),
            "run 2": (2, "stanley", mission[1]),
            "no run": (None, None, None),
        }, fmt
        assert [body[k]["sampleCount"] for k in body] == [5, 4, 5], fmt


@pytest.mark.parametrize(
    "content",
    [HEADER, to_csv([]).encode(), to_json([]).encode(), to_mcap([])],
    ids=["seed CSV header", "CSV header", "JSON export", "MCAP export"],
)
@pytest.mark.parametrize(
    "by", [[], ["--by", "run"], ["--by", "algorithm"], ["--json"]], ids=lambda by: " ".join(by) or "table"
)
def test_an_export_with_no_samples_says_so(tmp_path, content, by):
    """Issue 46: a header-only CSV printed nothing (`--by run`) or nine zeros, exit 0. Like every file
    `stats` cannot give figures for: one line naming it, exit 1."""
    f = tmp_path / "empty_export"
    f.write_bytes(content)
    r = run(f, *by)
    assert (r.returncode, r.stdout) == (1, "")
    assert r.stderr.splitlines() == [f"arbiter-tui stats: {f}: no samples"]


@pytest.fixture(scope="module")
def odometry_only(tmp_path_factory):
    """A recording with no goal and no plan (as evo's test bag: odometry, no /goal_pose, no /plan): a
    robot driven about by something the recording does not show."""
    rec = drive("pure_pursuit", goal=(2.0, 1.0), seconds=8.0)
    only = Recording([m for m in rec.messages if m[0] == "/odom"], rec.poses)
    return write_bag(tmp_path_factory.mktemp("bags") / "odom_only", only, "mcap")


ERRORS = ("avgDistanceError", "avgHeadingError", "stdDevError", "p95Error")


def test_a_recording_with_no_goal_or_plan_has_no_error_not_zero(odometry_only):
    """Issue 54, item 4: with no reference there is no error: '—' and why, null in JSON, never 0."""
    r = run(odometry_only)
    assert r.returncode == 0, r.stderr
    lines = dict(line.split(None, 1) for line in r.stdout.splitlines())
    for name in ERRORS:
        assert lines[name] == "— (no reference: no goal or plan in the recording, so no error to measure)"
    assert float(lines["avgLinearVel"].split()[0]) > 0.1 and int(lines["sampleCount"]) > 10
    r = run(odometry_only, "--json")
    got = json.loads(r.stdout)
    assert list(got) == [*STATS_FIELDS, "noReference"] and got["noReference"].startswith("no reference")
    assert all(got[name] is None for name in ERRORS) and got["totalPathLength"] > 1.0
    r = run(odometry_only, "--by", "run", "--json")
    assert all(json.loads(r.stdout)["no run"][name] is None for name in ERRORS)
