import csv
import io
import json
import math
import os
import stat
from dataclasses import replace

import pytest

from arbiter_tui.analytics.exports import (
    CSV_HEADER,
    MCAP_ODOM_TOPIC,
    MCAP_POINT_TOPIC,
    MCAP_RUNS_TOPIC,
    MCAP_STATS_TOPIC,
    SEED_CSV_HEADER,
    ExportFormatError,
    js_number,
    parse_csv,
    parse_json,
    parse_mcap,
    to_csv,
    to_json,
    to_mcap,
)
from arbiter_tui.analytics.files import ExportError, export_store, load_points, write_new_file
from arbiter_tui.analytics.store import FIELDS, AnalyticsStore, DataPoint, stats_of_points

from ..support.points import random_points


def test_csv_header_is_the_seeds_then_the_run_id_and_the_gap():
    seed = "timestamp,x,y,theta,linearVel,angularVel,distanceError,headingError,algorithm,latencyMs"
    assert seed + ",runId,gap" == CSV_HEADER
    assert to_csv([]).splitlines()[0] == CSV_HEADER


def test_the_seeds_own_csv_and_ours_before_the_gap_read_back():
    pts = random_points(5, seed=9)
    seed_csv = "\n".join(line.rsplit(",", 2)[0] for line in to_csv(pts).splitlines()) + "\n"
    assert seed_csv.splitlines()[0] == SEED_CSV_HEADER
    assert parse_csv(seed_csv) == [replace(p, runId=None) for p in pts]
    runs_csv = "\n".join(line.rsplit(",", 1)[0] for line in to_csv(pts).splitlines()) + "\n"
    assert parse_csv(runs_csv) == pts  # eleven columns: runId, no gap
    with pytest.raises(ExportFormatError, match="line 2: expected 10 columns"):
        parse_csv(SEED_CSV_HEADER + "\n1,2\n")


def test_a_gap_survives_every_format_and_its_step_is_not_in_the_path(tmp_path):
    """A sample that follows a gap (the link was down) says so in CSV (1), JSON (true) and MCAP, and the
    jump into it (the odometry back at the origin after a backend restart) is no path."""
    pts = [DataPoint(1000.0 + 100 * i, 0.1 * i, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, "manual", 1.0)
           for i in range(5)]  # fmt: skip
    pts += [DataPoint(9000.0 + 100 * i, 0.1 * i, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, "manual", 1.0, gap=i == 0)
            for i in range(3)]  # fmt: skip
    assert stats_of_points(pts).totalPathLength == pytest.approx(0.4 + 0.2)
    assert to_csv(pts).splitlines()[6].endswith(",,1")
    assert parse_csv(to_csv(pts)) == pts
    assert parse_json(to_json(pts)) == pts
    assert parse_mcap(to_mcap(pts)) == pts
    with pytest.raises(ExportFormatError, match="line 2: gap"):
        parse_csv(to_csv(pts[:1]).replace(",,\n", ",,yes\n"))


@pytest.mark.parametrize("bad", ["0", "-3", "1.5", "x", str(2**32)])
def test_a_bad_run_id_is_a_clear_error(bad):
    text = to_csv(random_points(1, seed=1))
    head, row = text.splitlines()
    cells = row.split(",")
    cells[-2] = bad  # the runId column
    with pytest.raises(ExportFormatError, match="line 2: runId"):
        parse_csv(f"{head}\n{','.join(cells)}\n")


def test_js_number_formatting():
    assert js_number(1712345678901.0) == "1712345678901"
    assert js_number(0.1) == "0.1"
    assert js_number(-2.5) == "-2.5"
    assert js_number(1e-7) == "1e-7"
    assert js_number(None) == ""
    with pytest.raises(ValueError):
        js_number(math.nan)


def test_csv_round_trip_through_the_csv_module():
    pts = random_points(50, seed=3, runs=True)
    text = to_csv(pts)
    rows = list(csv.DictReader(io.StringIO(text)))
    assert len(rows) == 50
    assert list(rows[0]) == [*FIELDS, "runId", "gap"]
    assert {r["runId"] for r in rows} == {"", "1", "2", "70000"}
    for p, row in zip(pts, rows, strict=False):
        assert float(row["x"]) == p.x
        assert row["algorithm"] == p.algorithm
        assert (row["latencyMs"] == "") == (p.latencyMs is None)
    assert parse_csv(text) == pts


def test_json_is_strict_and_round_trips():
    pts = random_points(30, seed=4, runs=True)
    text = to_json(pts)
    assert "NaN" not in text and "Infinity" not in text
    doc = json.loads(text)
    assert set(doc) == {"dataPoints", "stats"}  # summaries only when given (a store export gives them)
    assert list(doc["dataPoints"][0]) == [*FIELDS, "runId", "gap"]
    assert doc["stats"] == stats_of_points(pts).as_dict()
    assert parse_json(text) == pts


def test_mcap_reads_back_with_the_mcap_reader():
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    pts = random_points(20, seed=5, runs=True)
    data = to_mcap(pts)
    reader = make_reader(io.BytesIO(data), decoder_factories=[DecoderFactory()])
    summary = reader.get_summary()
    assert {c.topic for c in summary.channels.values()} == {
        MCAP_POINT_TOPIC,
        MCAP_STATS_TOPIC,
        MCAP_ODOM_TOPIC,
        MCAP_RUNS_TOPIC,
    } - {MCAP_RUNS_TOPIC}  # fmt: skip  (no runs given: no run messages, and no channel either)
    msgs = list(reader.iter_decoded_messages())
    points = [m for m in msgs if m.channel.topic == MCAP_POINT_TOPIC]
    assert len(points) == 20
    for p, (_schema, _channel, message, decoded) in zip(pts, points, strict=False):
        assert decoded.x == p.x and decoded.distance_error == p.distanceError
        assert decoded.algorithm == p.algorithm
        assert decoded.has_latency == (p.latencyMs is not None)
        assert decoded.run_id == (p.runId or 0)
        assert message.log_time == int(p.timestamp * 1_000_000)
    assert parse_mcap(data) == pts
    stats = next(d for _s, c, _m, d in msgs if c.topic == MCAP_STATS_TOPIC)
    assert stats.sample_count == 20
    assert stats.p95_error == stats_of_points(pts).p95Error


def test_mcap_refuses_invalid_points_before_writing():
    bad = DataPoint(0, 0, 0, 0, 0, 0, 0, 0, "manual", None)
    object.__setattr__(bad, "x", math.nan)
    with pytest.raises(ValueError):
        to_mcap([bad])


def test_write_new_file_never_overwrites(tmp_path):
    a = write_new_file(tmp_path, "arbiter_analytics_1", "csv", b"one")
    b = write_new_file(tmp_path, "arbiter_analytics_1", "csv", b"two")
    assert a.name == "arbiter_analytics_1.csv" and b.name == "arbiter_analytics_1_1.csv"
    assert a.read_bytes() == b"one" and b.read_bytes() == b"two"
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "arbiter_analytics_1.csv",
        "arbiter_analytics_1_1.csv",
    ]


def store_with(n: int) -> AnalyticsStore:
    s = AnalyticsStore()
    s.start_collection()
    for p in random_points(n, seed=1):
        s.record(p)
    return s


@pytest.mark.parametrize("fmt", ["csv", "json", "mcap"])
def test_export_store_names_and_contents(tmp_path, fmt):
    s = AnalyticsStore()
    s.start_collection()
    pts = random_points(10, seed=6)
    for p in pts:
        s.record(p)
    path = export_store(s, fmt, tmp_path, clock_ms=lambda: 1712345678901)
    assert path.name == f"arbiter_analytics_1712345678901.{fmt}"
    if fmt != "mcap":
        assert load_points(path) == pts
    assert len(s) == 10


@pytest.mark.skipif(os.geteuid() == 0, reason="root ignores directory permissions")
def test_unwritable_directory_is_a_clear_error(tmp_path):
    d = tmp_path / "ro"
    d.mkdir()
    d.chmod(stat.S_IRUSR | stat.S_IXUSR)
    s = store_with(1)
    with pytest.raises(ExportError):
        export_store(s, "csv", d)


def test_missing_directory_is_a_clear_error_and_leaves_nothing(tmp_path):
    s = store_with(1)
    with pytest.raises(ExportError, match="does not exist"):
        export_store(s, "json", tmp_path / "nope")
    assert list(tmp_path.iterdir()) == []


def test_full_disk_leaves_no_partial_file(tmp_path, monkeypatch):
    import arbiter_tui.analytics.files as files

    real_fdopen = os.fdopen

    class FullFile(io.RawIOBase):
        def __init__(self, fh):
            self.fh = fh

        def write(self, b):
            raise OSError(28, "No space left on device")

        def __enter__(self):
            return self

        def __exit__(self, *a):
            self.fh.close()

    monkeypatch.setattr(files.os, "fdopen", lambda fd, mode: FullFile(real_fdopen(fd, mode)))
    s = AnalyticsStore()
    s.start_collection()
    s.record(random_points(1)[0])
    with pytest.raises(ExportError, match="No space left"):
        export_store(s, "csv", tmp_path)
    assert list(tmp_path.iterdir()) == []
    assert len(s) == 1


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "empty"),
        ("a,b,c\n1,2,3\n", "header"),
        (CSV_HEADER + "\n1,2,3\n", "columns"),
        (CSV_HEADER + "\n1,2,3,4,5,6,7,8,manual,zz,,\n", "not a number"),
        (CSV_HEADER + "\n1,2,3,4,5,6,7,nan,manual,1,3,\n", "not finite"),
        (SEED_CSV_HEADER + "\n1,2,3,4,5,6,7,8,manual,zz\n", "not a number"),
        ('{"dataPoints": 5}', "dataPoints"),
        ('{"dataPoints": [{"x": 1}]}', "missing field"),
        ('{"dataPoints": [], "stats": NaN}', "non-standard"),
        ("{broken", "invalid JSON"),
    ],
)
def test_bad_exports_are_format_errors(tmp_path, content, message):
    f = tmp_path / "bad.txt"
    f.write_text(content)
    with pytest.raises(ExportFormatError, match=message):
        load_points(f)


def test_unwritable_directory_even_for_root():
    s = store_with(1)
    with pytest.raises(ExportError, match="cannot write"):
        export_store(s, "csv", "/proc")


def test_mcap_run_summaries_decode_with_the_mcap_reader():
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    store = AnalyticsStore()
    store.start_collection()
    for outcome in ("completed", "overridden"):
        run = store.begin_run("pure_pursuit", "figure_eight", 1_700_000_000_000.0)
        for p in random_points(15, seed=run):
            store.record(DataPoint(**{**p.as_dict(), "runId": run}))
        store.end_run(outcome, 1_700_000_009_000.0, 0.12 if outcome == "completed" else None)
    data = to_mcap(store.points(), store.stats(), store.runs())
    reader = make_reader(io.BytesIO(data), decoder_factories=[DecoderFactory()])
    runs = [d for _s, _c, _m, d in reader.iter_decoded_messages(topics=[MCAP_RUNS_TOPIC])]
    assert [(r.id, r.outcome, r.completed) for r in runs] == [
        (1, "completed", True),
        (2, "overridden", False),
    ]
    assert runs[0].final_error_m == 0.12 and math.isnan(runs[1].final_error_m)
    assert runs[0].time_s == 9.0 and runs[0].stats.sample_count == 15
    assert runs[1].stats.p95_error == store.runs()[1].stats.p95Error
    assert sorted(p.runId for p in parse_mcap(data)) == [1] * 15 + [2] * 15


@pytest.mark.parametrize("ms", [366.5001, 366.4999, 1234.5678])
def test_an_open_runs_time_reads_back_alike_from_the_json_and_the_mcap_export(ms):
    """A run still open has no end: both readers take its time from the file's figure. The JSON export
    rounds it to the millisecond (as the screen shows it); the MCAP export carried the float, and `stats
    --by run` on the journal said 0.367 s where the JSON export said 0.366 (tests/integration/
    test_ssh_link.py, once in a full run)."""
    from arbiter_tui.analytics.exports import read_json, read_mcap
    from arbiter_tui.analytics.runs import RunSummary

    pts = random_points(20, seed=5, runs=True)
    stats = stats_of_points(pts)
    run = RunSummary(1, "manual", "", 1000.0, None, "running", 0.12345678, stats, 10, 1000.0 + ms, None)
    from_json = read_json(to_json(pts, runs=[run])).runs
    from_mcap = read_mcap(to_mcap(pts, runs=[run])).runs
    assert from_json is not None and from_mcap is not None
    assert round(from_json[0].time_s, 3) == round(from_mcap[0].time_s, 3) == round(ms / 1000, 3)
    assert from_json[0].final_error_m == from_mcap[0].final_error_m == 0.1235
