"""The backend beside a graph shaped like a real robot's (issue 53, item 4, with the [ros] extra).

``tests/support/robotgraph.py`` brings up a Nav2-shaped graph in two waves: lifecycle nodes, seven
action servers, introspected services, Nav2's topics at their rates, a hundred more and a second robot
under ``/robot2``. ``arbiter-backend --transport ros`` runs beside it as the robot's backend (its
simulated base publishes ``/odom``). For a minute the test asks ``/api/topics`` once a second, as the
console's topics screen does, while an observe-mode console grades the foreign controller that drives
the base through the ``follow_path`` action, then stops it. Then:

- ``/odom`` was never reported silent while it flowed; every topic the graph publishes is measured
  within 10 % of the rate it really had (its publish times over the monitor's window, as
  ``test_topics_ros`` computes the truth);
- the action topics and the service events are listed with their types, the second wave's too;
- ``/api/health`` shows every worker of the backend running, none restarted;
- the console graded the run the foreign controller drove, and its stop cancelled the goal: the
  action server saw the cancel, and the base stands.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx
import pytest

from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.session.robot import RobotSession
from arbiter_tui.session.settings import Settings

from ..support.backend import start_backend
from ..support.ros import domain, use_test_domain
from ..support.truth import steady
from ..support.waits import wait_for

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)

GRAPH = Path(__file__).resolve().parents[1] / "support" / "robotgraph.py"
WATCH_S = 60.0  # the minute
REL = 0.10
ACTIONS = (
    "/navigate_to_pose", "/follow_path", "/compute_path_to_pose", "/spin", "/backup", "/drive_on_heading",
    "/follow_waypoints", "/robot2/follow_path",
)  # fmt: skip
EVENT = "/lifecycle_manager_navigation/is_active/_service_event"


class GraphProc:
    """The graph in a child process (its timers must not share this process's GIL with the polling)."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, str(GRAPH), *args],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env={**os.environ, "ROS_DOMAIN_ID": str(domain())},
        )
        self.lines: list[str] = []
        self._dumps: list[dict] = []
        self._got = threading.Condition()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            with self._got:
                if line.startswith("{"):
                    self._dumps.append(json.loads(line))
                else:
                    self.lines.append(line.strip())
                self._got.notify_all()

    def said(self, line: str, timeout: float) -> bool:
        with self._got:
            return self._got.wait_for(lambda: line in self.lines, timeout)

    def send(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def dump(self) -> dict:
        with self._got:
            n = len(self._dumps)
            self.send("dump")
            assert self._got.wait_for(lambda: len(self._dumps) > n, 20), "the graph did not answer"
            return self._dumps[-1]

    def close(self) -> None:
        if self.proc.poll() is None:
            self.send("quit")
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)


def topics(api: str) -> dict[str, dict]:
    return {t["name"]: t for t in httpx.get(f"{api}/api/topics", timeout=5).json()["topics"]}


def off_rates(got: dict[str, dict], sent: dict, asked_at: float, window: float) -> dict[str, tuple]:
    """The steadily flowing topics whose measured rate is not within ``REL`` of the truth over the window
    ending when they were asked for, or that were called silent: name -> (truth, measured, state)."""
    bad = {}
    for name, times in sent["times"].items():
        rate = steady(times, asked_at - window, asked_at)
        if rate is None:
            continue
        row = got.get(name) or {}
        measured = row.get("rate_hz")
        if not measured or abs(measured - rate) > REL * rate or row.get("state") in ("silent", "unknown"):
            bad[name] = (round(rate, 2), measured, row.get("state"))
    return bad


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_beside_a_nav2_shaped_graph_every_topic_is_measured_and_a_foreign_goal_is_graded_and_stopped(
    tmp_path,
):
    backend = start_backend("--transport", "ros", timeout=30)
    graph = GraphProc("--hub", "100", "--wave2-after", "4")
    settings = Settings(
        handle_signals=False, export_dir=tmp_path, observe=True, observe_label="foreign_follow_path",
        cmd_topic="/cmd_vel", cmd_stamped=True, status_topic="/follow_path/_action/status",
        stop_actions=("follow_path",),
    )  # fmt: skip
    link = RosLink("127.0.0.1", backend.bridge_port)
    session = RobotSession(settings, link)
    try:
        assert graph.said("ready 1", 60), graph.lines
        assert wait_for(lambda: link.state == CONNECTED and link.telemetry.odom_count > 0, 30)
        assert graph.said("ready 2", 60), graph.lines
        window = httpx.get(f"{backend.api}/api/topics", timeout=5).json()["window_s"]

        # -- a minute of asking, as the topics screen does; a goal driven and stopped meanwhile --------
        start, polls, silent_odom = time.monotonic(), [], []
        goal_sent = stop_at = None
        while (now := time.monotonic()) - start < WATCH_S:
            got = topics(backend.api)
            polls.append((time.monotonic(), got))
            odom = got.get("/odom")
            if now - start > window and (
                odom is None or odom.get("state") == "silent" or not odom["rate_hz"]
            ):
                silent_odom.append((round(now - start, 1), odom))
            if goal_sent is None and now - start > 5:
                graph.send("goal 4.0 1.0")  # 4.1 m at 0.2 m/s: it drives until stopped
                goal_sent = now
            if goal_sent and stop_at is None and link.telemetry.v > 0.1 and now - goal_sent > 6:
                session.stop_all("stop key")
                stop_at = time.monotonic()
            time.sleep(max(0.0, now + 1.0 - time.monotonic()))  # pacing: a poll a second, as the screen
        assert not silent_odom, f"/odom flowed at 50 Hz but was reported: {silent_odom[:3]}"

        # -- the foreign controller's run: graded, and stopped by the stop key ----------------------
        assert stop_at is not None, "the follow_path goal never drove the base"
        sent = graph.dump()
        (goal,) = sent["goals"]
        assert goal["ended"] == "canceled", goal
        assert goal["at"] - stop_at < 1.5, ("cancel arrived late", goal["at"] - stop_at)
        assert wait_for(lambda: max(abs(link.telemetry.v), abs(link.telemetry.w)) < 0.01, 5)
        assert session.remote_stop.wait_idle(10)
        report = session.remote_stop.reports[-1]
        assert "cancelled 1 goal of /follow_path" in report.text(), report.text()
        runs = [r for r in session.store.runs() if r.algorithm == "foreign_follow_path"]
        assert runs, session.store.runs()
        run = runs[-1]
        samples = [p for p in session.store.points() if p.runId == run.id]
        assert len(samples) > 20 and run.tracking is not None, (len(samples), run)
        assert any(p.latencyMs is not None for p in samples), "the TwistStamped's age is the latency"

        # -- the whole minute: every steadily flowing topic within 10 % of the truth, none called silent;
        # a poll or two may be off on a loaded machine (a burst of late deliveries moves a few messages
        # across the window's edge: test_topics_ros), never a topic for long ---------------------------
        settled = [(at, got) for at, got in polls if at - start > window + 1.0]
        offs = [off_rates(got, sent, at, window) for at, got in settled]
        counted = {
            name
            for at, _ in settled
            for name in sent["times"]
            if steady(sent["times"][name], at - window, at)
        }
        # Nav2's thirteen periodic topics, the hub's hundred, the second robot's three, /odom; the goal's
        assert len(counted) >= 117 and {"/odom", "/scan", "/imu/data", "/robot2/odom", "/cmd_vel"} <= counted
        for name in counted:
            off = [o[name] for o in offs if name in o]
            assert len(off) <= 0.1 * len(settled), f"{name} off the truth by over {REL:.0%} or silent: {off}"
        final = polls[-1][1]

        # -- what is not a plain topic is listed, with its type --------------------------------------
        for action in ("/follow_path", "/robot2/follow_path", "/spin", "/navigate_to_pose"):
            assert final[f"{action}/_action/status"]["type"] == "action_msgs/msg/GoalStatusArray"
            assert final[f"{action}/_action/feedback"]["type"] == "test_msgs/action/Fibonacci_FeedbackMessage"
        assert final[EVENT]["type"] == "std_srvs/srv/Trigger_Event"
        assert final[EVENT]["rate_hz"], final[EVENT]
        assert final["/controller_server/transition_event"]["type"] == "lifecycle_msgs/msg/TransitionEvent"
        hub = [n for n in final if n.startswith("/hub/sensor_")]
        assert len(hub) == 100 and "/robot2/odom" in final

        # -- every worker of the backend up, none restarted -----------------------------------------
        health = httpx.get(f"{backend.api}/api/health", timeout=5).json()
        workers = health["workers"]
        assert workers and all(w["state"] == "running" and w["restarts"] == 0 for w in workers), workers
    finally:
        session.close()
        link.close()
        graph.close()
        backend.stop()
