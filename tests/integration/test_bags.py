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
    # the plan and goal are in 'map', the odometry in 'odom': said once each, not hidden
    warnings = outs[0].stderr.strip().splitlines()
    assert len(warnings) == 2 and all("in frame 'map', odometry in 'odom'" in w for w in warnings), warnings
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
    export = read_bag(mcap)
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
    export = read_bag(bag)
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
    from ..support.bags import TS, Recording

    chatter = Recording(messages=[("/chatter", 1, TS.types["std_msgs/msg/String"](data="hi"))])
    foreign = write_bag(tmp_path / "foreign", chatter, "mcap")
    for bag, said in (
        (cut_mcap, "damaged or unreadable ros2 bag"),
        (cut_db3, "damaged or unreadable ros2 bag"),
        (foreign, "ros2 bag without odometry on /odom (it has /chatter)"),
    ):
        out = stats(bag)
        assert out.returncode == 1, out.stdout
        assert said in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr
        assert "Traceback" not in out.stderr
    out = stats(mcap, "--odom-topic", "/plan")
    assert out.returncode == 1 and "/plan is nav_msgs/msg/Path, not nav_msgs/msg/Odometry" in out.stderr
