"""``arbiter-tui stats BAG_DIR``: a robot-side controller's run recorded as a ros2 bag (MCAP and SQLite 3,
written with rosbags as ``ros2 bag record`` writes them), graded as the console grades its own runs."""

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from arbiter_tui.analytics import tracking as T
from arbiter_tui.analytics.bags import read_bag

from ..support.bags import drive, write_bag


def stats(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "arbiter_tui.cli", "stats", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=60,
    )


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    rec = drive("pure_pursuit", goal=(2.0, 1.0))
    root = tmp_path_factory.mktemp("bags")
    return rec, write_bag(root / "run_mcap", rec, "mcap"), write_bag(root / "run_db3", rec, "sqlite3")


def test_an_mcap_and_an_sqlite_bag_of_one_run_give_the_same_stats_and_tracking(bags):
    _rec, mcap, db3 = bags
    outs = [stats(bag, "--by", "run", "--json", "--label", "rpp_on_robot") for bag in (mcap, db3)]
    assert [o.returncode for o in outs] == [0, 0], [o.stderr for o in outs]
    assert outs[0].stdout == outs[1].stdout
    # the plan and goal are in 'map', the odometry in 'odom': said once, not hidden (it said it twice)
    (warning,) = outs[0].stderr.strip().splitlines()
    assert "/goal_pose and /plan are in frame 'map', odometry in 'odom'" in warning, warning
    body = json.loads(outs[0].stdout)
    run = body["run 1"]
    assert (run["algorithm"], run["mission"], run["outcome"]) == (
        "rpp_on_robot",
        "goal (+2.00, +1.00)",
        "completed",
    )
    assert run["sampleCount"] > 20 and run["tracking"]["samples"] == run["sampleCount"]
    text = stats(mcap, "--by", "run")
    assert text.returncode == 0 and "[run 1 observed on goal (+2.00, +1.00)]" in text.stdout
    assert "outcome" in text.stdout and "xteMean" in text.stdout


def test_the_observed_runs_tracking_equals_the_true_poses_against_the_plan(bags):
    """The simulator's true pose at each sample's time, against the recorded plan: the same figures."""
    rec, mcap, _db3 = bags
    export = read_bag(mcap).export
    (run,) = export.runs
    samples = [p for p in export.points if p.runId == run.id]
    truth = dict((t // 1_000_000, (x, y)) for t, x, y in rec.poses)
    xy = np.array([truth[int(p.timestamp)] for p in samples])
    plan = next(m for topic, _t, m in rec.messages if topic == "/plan")
    path = np.array([(p.pose.position.x, p.pose.position.y) for p in plan.poses])
    xte = T.cross_track(xy[:, 0], xy[:, 1], path)
    assert run.tracking.xte_mean_m == pytest.approx(float(xte.mean()), abs=0.01)
    assert run.tracking.xte_max_m == pytest.approx(float(xte.max()), abs=0.01)
    assert all(p.latencyMs == pytest.approx(3.0) for p in samples[1:])  # TwistStamped: 3 ms old on arrival


def test_a_plain_twist_bag_has_no_latency_and_still_grades_the_run(tmp_path):
    rec = drive("go_to_goal", goal=(1.5, -0.5), stamped=False)
    bag = write_bag(tmp_path / "twist", rec, "mcap", extra={"/cmd_vel": "geometry_msgs/msg/Twist"})
    export = read_bag(bag).export
    assert [r.outcome for r in export.runs] == ["completed"]
    assert all(p.latencyMs is None for p in export.points)


def test_truncated_foreign_and_mistyped_bags_are_one_line_each(bags, tmp_path):
    _rec, mcap, db3 = bags
    cut_mcap = shutil.copytree(mcap, tmp_path / "cut_mcap")
    data = next(cut_mcap.glob("*.mcap"))
    data.write_bytes(data.read_bytes()[: data.stat().st_size // 2])
    cut_db3 = shutil.copytree(db3, tmp_path / "cut_db3")
    data = next(cut_db3.glob("*.db3"))
    data.write_bytes(data.read_bytes()[: data.stat().st_size // 3])
    lone_cut_db3 = shutil.copy(data, tmp_path / "lone_cut.db3")  # a lone file is never taken for a cut MCAP
    from ..support.bags import TS, Recording

    chatter = Recording(messages=[("/chatter", 1, TS.types["std_msgs/msg/String"](data="hi"))])
    foreign = write_bag(tmp_path / "foreign", chatter, "mcap")
    for bag, said in (
        (cut_mcap, "truncated MCAP storage file"),
        (cut_db3, "damaged or unreadable ros2 bag"),
        (lone_cut_db3, "damaged or unreadable ros2 bag"),
        (foreign, "has no odometry on /odom (it has /chatter)"),
    ):
        out = stats(bag)
        assert out.returncode == 1, out.stdout
        assert said in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr
        assert "Traceback" not in out.stderr
        assert bag == cut_mcap or "mcap recover" not in out.stderr, out.stderr
    out = stats(mcap, "--odom-topic", "/plan")
    assert out.returncode == 1 and "/plan is nav_msgs/msg/Path, not nav_msgs/msg/Odometry" in out.stderr


# -- what the field hands you (issue 47) ------------------------------------------------------------------


def _json(out: subprocess.CompletedProcess) -> dict:
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def test_a_lone_mcap_or_db3_file_grades_as_its_bag_directory(bags, tmp_path):
    """How such files are shared: the storage file alone (main refused a lone .mcap as "not an arbiter
    analytics export" and a .db3 as "an SQLite database")."""
    _rec, mcap, db3 = bags
    for bag, suffix in ((mcap, ".mcap"), (db3, ".db3")):
        lone = tmp_path / f"shared{suffix}"
        shutil.copy(next(bag.glob(f"*{suffix}")), lone)
        assert _json(stats(lone, "--by", "run", "--json")) == _json(stats(bag, "--by", "run", "--json"))


def _split(rec, at_ns: int) -> tuple:
    from ..support.bags import Recording

    head = Recording([m for m in rec.messages if m[1] < at_ns])
    tail = Recording([m for m in rec.messages if m[1] >= at_ns])
    return head, tail


def test_a_split_bag_with_or_without_its_metadata_grades_as_one_file(bags, tmp_path):
    """Two storage files (``ros2 bag record --max-bag-duration``): with a metadata.yaml naming both, and
    without one (a killed recorder: main said only "is a directory"), read in split order, with a note."""
    import yaml

    rec, mcap, _db3 = bags
    head, tail = _split(rec, rec.messages[len(rec.messages) // 2][1])
    parts = [write_bag(tmp_path / f"part{i}", r, "mcap") for i, r in enumerate((head, tail))]
    split = tmp_path / "split"
    split.mkdir()
    for i, part in enumerate(parts):
        shutil.copy(next(part.glob("*.mcap")), split / f"split_{i}.mcap")
    bare = shutil.copytree(split, tmp_path / "bare")  # no metadata.yaml
    meta = [yaml.safe_load((p / "metadata.yaml").read_text())["rosbag2_bagfile_information"] for p in parts]
    info = dict(meta[0])
    info["relative_file_paths"] = ["split_0.mcap", "split_1.mcap"]
    info["files"] = [dict(m["files"][0], path=f"split_{i}.mcap") for i, m in enumerate(meta)]
    info["message_count"] = sum(m["message_count"] for m in meta)
    first = meta[0]["starting_time"]["nanoseconds_since_epoch"]
    last = max(m["starting_time"]["nanoseconds_since_epoch"] + m["duration"]["nanoseconds"] for m in meta)
    info["duration"] = {"nanoseconds": last - first}
    counts: dict[str, dict] = {}
    for m in meta:
        for t in m["topics_with_message_count"]:
            name = t["topic_metadata"]["name"]
            counts.setdefault(name, dict(t, message_count=0))["message_count"] += t["message_count"]
    info["topics_with_message_count"] = list(counts.values())
    (split / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}))
    whole = _json(stats(mcap, "--by", "run", "--json"))
    assert _json(stats(split, "--by", "run", "--json")) == whole
    out = stats(bare, "--by", "run", "--json")
    assert _json(out) == whole
    (note,) = out.stderr.strip().splitlines()[:1]
    assert "no metadata.yaml" in note and "2 storage files" in note and f"ros2 bag reindex {bare}" in note


@pytest.mark.parametrize("compression", ["file", "message"])
def test_zstd_compressed_bags_grade_as_the_plain_one(bags, tmp_path, compression):
    rec, mcap, _db3 = bags
    for storage in ("mcap", "sqlite3"):
        packed = write_bag(tmp_path / f"{compression}_{storage}", rec, storage, compression=compression)
        assert _json(stats(packed, "--by", "run", "--json")) == _json(stats(mcap, "--by", "run", "--json"))
    if compression == "message":  # the files alone, without the metadata that says so: each message says
        bare = tmp_path / "bare"
        bare.mkdir()
        shutil.copy(next((tmp_path / "message_mcap").glob("*.mcap")), bare)
        assert _json(stats(bare, "--by", "run", "--json")) == _json(stats(mcap, "--by", "run", "--json"))


SERVICE_EVENT = (
    "/controller_server/get_parameters/_service_event",
    "rcl_interfaces/srv/GetParameters_Event",
    "# a service's request and response: not a message definition a msg parser reads\n"
    "string[] names\n---\nParameterValue[] values\n",
)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_topic_of_a_type_nobody_parses_does_not_refuse_the_bag(tmp_path, storage):
    """Service events (srv schemas) beside the odometry: main refused the whole bag with "Could not
    parse:"; only the graded topics' definitions are parsed now."""
    rec = drive("pure_pursuit", goal=(1.0, 0.5), seconds=8.0)
    raw = [(*SERVICE_EVENT, rec.messages[10][1] + 5, b"\x00\x01\x00\x00garbage")]
    bag = write_bag(tmp_path / "events", rec, storage, raw=raw)
    body = _json(stats(bag, "--by", "run", "--json"))
    assert body["run 1"]["outcome"] == "completed"


def test_an_empty_odometry_topic_is_one_line_not_zeros(tmp_path):
    """main printed nine zeros and exited 0."""
    from ..support.bags import Recording

    rec = drive("pure_pursuit", goal=(1.0, 0.5), seconds=3.0)
    no_odom = Recording([m for m in rec.messages if m[0] != "/odom"])
    bag = write_bag(tmp_path / "empty_odom", no_odom, "mcap", empty={"/odom": "nav_msgs/msg/Odometry"})
    out = stats(bag)
    assert out.returncode == 1 and out.stdout == ""
    (line,) = out.stderr.strip().splitlines()
    assert "has no messages on /odom" in line and str(bag) in line


def test_by_algorithm_on_a_bag_without_runs_says_so(tmp_path):
    """Odometry alone: no goal ever came. main printed nothing (``{}`` with --json) and exited 0."""
    from ..support.bags import Recording

    rec = drive("pure_pursuit", goal=(1.0, 0.5), seconds=3.0)
    bag = write_bag(tmp_path / "odom_only", Recording([m for m in rec.messages if m[0] == "/odom"]), "mcap")
    for extra in ((), ("--json",)):
        for by in ("algorithm", "controller"):
            out = stats(bag, "--by", by, *extra)
            assert out.returncode == 1 and out.stdout == "", out.stdout
            (line,) = out.stderr.strip().splitlines()
            assert "no runs to group" in line and "/goal_pose" in line and "/plan" in line
    assert stats(bag, "--by", "run").returncode == 0  # its samples, outside every run


def test_a_truncated_mcap_says_which_file_and_what_to_run(bags, tmp_path):
    """A crashed recorder's MCAP (no footer): main said only "File end magic is invalid."."""
    _rec, mcap, _db3 = bags
    cut = shutil.copytree(mcap, tmp_path / "crashed")
    data = next(cut.glob("*.mcap"))
    data.write_bytes(data.read_bytes()[: data.stat().st_size * 2 // 3])
    lone = tmp_path / "lone.mcap"
    shutil.copy(data, lone)
    for target, also in ((cut, f"ros2 bag reindex {cut}"), (lone, "mcap recover")):
        out = stats(target)
        assert out.returncode == 1
        (line,) = out.stderr.strip().splitlines()
        assert "truncated MCAP storage file" in line and "mcap recover" in line and also in line, line


def _straight(seconds: float, plans: list[tuple[int, list[tuple[float, float]]]], extra=()) -> object:
    """Odometry along y = 0 at 0.5 m/s from x = 0 (50 Hz), commands at 20 Hz (zero at the end), then 1 s
    standing; ``plans``: (log time from the start, points) each; ``extra``: more (topic, t, msg)."""
    from ..support.bags import T0_NS, Recording, _twist, odometry_msg, path_msg

    rec = Recording()
    n = round(seconds * 50)
    for k in range(n + 50):
        t = T0_NS + k * 20_000_000
        moving = k < n
        x = 0.5 * min(k, n) / 50
        if k % 5 in (0, 2) and k <= n:
            rec.messages.append(("/cmd_vel", t - 1_000_000, _twist(0.5 if moving else 0.0, 0.0)))
        pose = {"position": {"x": x, "y": 0.0}, "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}
        twist = {"linear": {"x": 0.5 if moving else 0.0}, "angular": {"z": 0.0}}
        odom = {"pose": {"pose": pose}, "twist": {"twist": twist}}
        rec.messages.append(("/odom", t, odometry_msg(t, odom)))
    for dt, points in plans:
        rec.messages.append(("/plan", T0_NS + dt, path_msg(T0_NS + dt, points)))
    rec.messages += list(extra)
    rec.messages.sort(key=lambda m: m[1])
    return rec


def line(y: float, x0: float, x1: float) -> list[tuple[float, float]]:
    return [(x0 + (x1 - x0) * k / 20, y) for k in range(21)]


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_replans_in_a_bag_measure_each_sample_against_the_plan_in_force(tmp_path, storage):
    """A run started by a plan alone, replanned every second (Nav2's default): 0.10 m beside the track
    for 4 s, then 0.03 m. main took the first replan as every sample's reference (0.10 for all)."""
    s = 1_000_000_000
    plans = [(0, line(0.10, -1.0, 4.0))] + [
        (k * s, line(0.10 if k < 4 else -0.03, 0.0, 4.0)) for k in range(1, 9)
    ]
    bag = write_bag(
        tmp_path / "replans", _straight(8.0, plans), storage, extra={"/cmd_vel": "geometry_msgs/msg/Twist"}
    )
    recording = read_bag(bag)
    (run,) = recording.export.runs
    samples = [p for p in recording.export.points if p.runId == run.id]
    switch_ms = (samples[0].timestamp // 1000 + 4) * 1000  # the replan at 4 s from the bag's start
    before = sum(1 for p in samples if p.timestamp < switch_ms + 0.5)
    expected = (before * 0.10 + (len(samples) - before) * 0.03) / len(samples)
    assert run.outcome == "completed" and 30 < before < len(samples) - 30
    assert run.tracking.xte_mean_m == pytest.approx(expected, abs=1e-9)
    assert run.tracking.path_ratio == pytest.approx(
        run.stats.totalPathLength / 5.0, abs=1e-9
    )  # the first plan


def test_the_action_status_in_a_bag_ends_the_run_with_its_outcome(tmp_path):
    """Nav2's navigator aborts its goal 2 s into the run: the run ends there, aborted (main ignored the
    status and graded the run as completed)."""
    from ..support.bags import T0_NS, status_msg

    s = 1_000_000_000
    topic = "/navigate_to_pose/_action/status"
    statuses = [(topic, T0_NS, status_msg(T0_NS, (1, 2))), (topic, T0_NS + 2 * s, status_msg(T0_NS, (1, 6)))]
    rec = _straight(6.0, [(1, line(0.0, 0.0, 3.0))], extra=statuses)
    bag = write_bag(tmp_path / "aborted", rec, "mcap", extra={"/cmd_vel": "geometry_msgs/msg/Twist"})
    run = _json(stats(bag, "--by", "run", "--json"))["run 1"]
    assert run["outcome"] == "aborted" and run["time_s"] == pytest.approx(2.0, abs=1e-3)


def test_scans_give_the_obstacle_figures_and_the_scorecards_say_why_where_they_cannot(tmp_path):
    """A LaserScan at 5 Hz whose nearest return is known: min, mean-min and its standard deviation over
    the scans taken during the run; returns out of [range_min, range_max] and scans with none left out."""
    from ..support.bags import T0_NS, scan_msg

    s = 1_000_000_000
    nearest = [0.9, 0.6, 0.45, 0.7, 1.2, 0.5, 0.8, 1.0, 0.65, 0.55] * 3  # one every 0.2 s over 6 s
    extra = []
    for i, d in enumerate(nearest):
        ranges = [3.0] * 360
        ranges[i * 7 % 360] = d
        ranges[(i * 7 + 90) % 360] = 0.05  # below range_min: not an obstacle
        ranges[(i * 7 + 180) % 360] = float("inf")
        extra.append(("/scan", T0_NS + i * s // 5 + 7, scan_msg(T0_NS, ranges)))
    extra.append(("/scan", T0_NS + 6 * s + 7, scan_msg(T0_NS, [float("inf")] * 360)))  # nothing in range
    rec = _straight(6.0, [(1, line(0.0, 0.0, 3.0))], extra=extra)
    bag = write_bag(tmp_path / "scan", rec, "mcap", extra={"/cmd_vel": "geometry_msgs/msg/Twist"})
    body = _json(stats(bag, "--by", "run", "--json"))["run 1"]
    card = body["scorecard"]
    recording = read_bag(bag)
    (run,) = recording.export.runs
    t_ms = [(T0_NS + i * s // 5 + 7) / 1e6 for i in range(len(nearest))]
    d = np.array([v for t, v in zip(t_ms, nearest, strict=True) if run.start_ms <= t <= run.end_ms])
    assert len(d) >= 25 and card["scans"] == len(d)
    assert card["min_obstacle_m"] == pytest.approx(d.min(), abs=1e-6)
    assert card["mean_min_obstacle_m"] == pytest.approx(d.mean(), abs=1e-6)
    assert card["std_min_obstacle_m"] == pytest.approx(d.std(), abs=1e-6)
    ctl = _json(stats(bag, "--by", "controller", "--json"))["controller observed"]
    assert ctl["runs"] == 1 and ctl["min_obstacle_m"] == card["min_obstacle_m"]
    # BARN: OT = 3 m / 2 m/s = 1.5 s; AT from the first sample 0.1 m out to the end (about 5.8 s)
    at = (
        run.end_ms / 1e3
        - next(p.timestamp for p in recording.export.points if p.runId == 1 and p.x >= 0.1) / 1e3
    )
    assert card["barn"] == pytest.approx(1.5 / min(max(at, 3.0), 12.0), abs=1e-6)
    # no scan topic: the reason, never 0
    plain = write_bag(tmp_path / "plain", _straight(6.0, [(1, line(0.0, 0.0, 3.0))]), "mcap",
                      extra={"/cmd_vel": "geometry_msgs/msg/Twist"})  # fmt: skip
    card = _json(stats(plain, "--by", "run", "--json"))["run 1"]["scorecard"]
    assert card["min_obstacle_m"] == {
        "value": None,
        "why": "no sensor_msgs/LaserScan on /scan in the recording",
    }
    text = stats(plain, "--by", "run").stdout
    assert "minObstacle       — (no sensor_msgs/LaserScan on /scan in the recording)" in text


def test_grade_returns_what_stats_prints_for_the_analytics_screen(bags):
    """The one function the analytics screen calls for a file: the same runs, in the order stats prints
    them, with their scorecards and the screen's ranking."""
    from arbiter_tui.analytics.grade import grade

    _rec, mcap, _db3 = bags
    graded = grade(mcap)
    body = _json(stats(mcap, "--by", "run", "--json"))
    assert [f"run {r.id}" for r in graded.runs] == [k for k in body if k.startswith("run ")]
    (run,) = graded.runs
    assert run.tracking.as_dict() == body["run 1"]["tracking"]
    assert graded.card(run.id).as_dict() == body["run 1"]["scorecard"]
    assert graded.is_bag and graded.what.startswith("ros2 bag directory (MCAP, 1 file")
    assert graded.ranking().missions[0].mission == run.mission
    assert len(graded.notes) == 1 and "in frame 'map'" in graded.notes[0]


def test_running_out_of_memory_is_said_as_such_never_as_a_damaged_file(bags, monkeypatch, capsys):
    from arbiter_tui.analytics import observe
    from arbiter_tui.cli import main

    _rec, mcap, _db3 = bags

    def no_memory(*_args: object) -> None:
        raise MemoryError

    monkeypatch.setattr(observe.Observer, "on_plan", no_memory)
    assert main(["stats", str(mcap)]) == 1
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "out of memory reading ros2 bag directory" in line and "not damaged" in line
    assert "damaged or unreadable" not in line


def test_a_bag_in_another_serialization_than_cdr_says_so(tmp_path):
    from rosbags.rosbag2 import Writer

    from ..support.bags import TS

    with Writer(tmp_path / "json", version=9) as writer:
        conn = writer.add_connection(
            "/odom", "nav_msgs/msg/Odometry", typestore=TS, serialization_format="json"
        )
        writer.write(conn, 1, b"{}")
    out = stats(tmp_path / "json")
    (line,) = out.stderr.strip().splitlines()
    assert out.returncode == 1 and "serialization other than CDR" in line and "json" in line, line
