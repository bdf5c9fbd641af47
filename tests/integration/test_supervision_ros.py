"""``--transport ros`` beside a graph with what every robot's has and the seed's tests never had: a service
with introspection on (its ``_service_event`` topic, of type ``pkg/srv/Name_Event``) and an action server
(``_action/feedback`` of type ``pkg/action/Name_FeedbackMessage``, ``_action/status``), called all the
while, and a 50 Hz ``/odom``. The topic monitor lists and measures them all; each supervised worker,
made to fail once (``ARBITER_FAULT``), is restarted and says so in ``/api/health``, and the odometry is
measured at its rate, never reported silent, throughout."""

import base64
import subprocess
import sys
import time

import httpx
import pytest
import roslibpy

from ..support.backend import start_backend
from ..support.ros import domain, use_test_domain
from ..support.waits import wait_for

ros_domain = pytest.fixture(scope="module", autouse=True)(use_test_domain)

WINDOW = 3.0
ODOM_HZ = 50.0
ROS_WORKERS = ("rclpy-executor", "rclpy-provider", "qos-follower", "topic-monitor")
HELD_BY = (("monitor", "topic-monitor"), ("executor", "rclpy-executor"))  # the topics' readers

# In a child process (its 50 Hz timer would compete for the GIL with the test's polling here): the
# robot's node, whose service is called at 5 Hz and whose action gets a goal a second (3 feedbacks each).
GRAPH = r"""
import sys, threading, time, rclpy
from rclpy.action import ActionClient, ActionServer
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.context import Context
from rclpy.executors import MultiThreadedExecutor
from rclpy.qos import qos_profile_system_default
from rclpy.service_introspection import ServiceIntrospectionState
from nav_msgs.msg import Odometry
from std_srvs.srv import Trigger
from test_msgs.action import Fibonacci

ctx = Context()
rclpy.init(context=ctx, domain_id=int(sys.argv[1]))
node = rclpy.create_node("arbiter_graph_robot", context=ctx)
group = ReentrantCallbackGroup()
srv = node.create_service(Trigger, "/arbiter_test/trigger", lambda req, resp: resp)
srv.configure_introspection(node.get_clock(), qos_profile_system_default, ServiceIntrospectionState.CONTENTS)

def execute(goal):
    for i in range(3):
        goal.publish_feedback(Fibonacci.Feedback(sequence=list(range(i + 1))))
        time.sleep(0.05)
    goal.succeed()
    return Fibonacci.Result()

server = ActionServer(node, Fibonacci, "/arbiter_test/fibonacci", execute, callback_group=group)
client = node.create_client(Trigger, "/arbiter_test/trigger", callback_group=group)
goals = ActionClient(node, Fibonacci, "/arbiter_test/fibonacci", callback_group=group)
odom = node.create_publisher(Odometry, "/arbiter_test/odom", 10)
node.create_timer(0.2, lambda: client.service_is_ready() and client.call_async(Trigger.Request()), group)
goal = Fibonacci.Goal(order=3)
node.create_timer(1.0, lambda: goals.server_is_ready() and goals.send_goal_async(goal), group)

def publish_odometry():  # on a schedule of its own: an executor's timer runs late on a loaded machine
    msg, due = Odometry(), time.monotonic()
    while True:
        odom.publish(msg)
        due += 1.0 / 50
        time.sleep(max(0.0, due - time.monotonic()))

threading.Thread(target=publish_odometry, daemon=True).start()
executor = MultiThreadedExecutor(num_threads=3, context=ctx)
executor.add_node(node)
print("ready", flush=True)
executor.spin()
"""
EVENTS = "/arbiter_test/trigger/_service_event"
FEEDBACK = "/arbiter_test/fibonacci/_action/feedback"
STATUS = "/arbiter_test/fibonacci/_action/status"
ODOM = "/arbiter_test/odom"


@pytest.fixture(scope="module")
def graph():
    proc = subprocess.Popen(
        [sys.executable, "-c", GRAPH, str(domain())],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None and proc.stdout.readline().strip() == "ready", proc.stderr.read()
    yield proc
    proc.terminate()
    proc.wait(10)


def topics(api: str) -> dict[str, dict]:
    return {t["name"]: t for t in httpx.get(f"{api}/api/topics", timeout=5).json()["topics"]}


def workers(api: str) -> dict[str, dict]:
    return {w["name"]: w for w in httpx.get(f"{api}/api/health", timeout=5).json().get("workers", [])}


def everything_measured(api: str) -> bool:
    """Every entity of the graph listed with its type, the service events and the feedback counted, the
    odometry at its rate over a whole window."""
    got = topics(api)
    odom = got.get(ODOM, {})
    return (
        got.get(EVENTS, {}).get("type") == "std_srvs/srv/Trigger_Event"
        and got[EVENTS]["total"] > 0
        and got.get(FEEDBACK, {}).get("type") == "test_msgs/action/Fibonacci_FeedbackMessage"
        and got[FEEDBACK]["total"] > 0
        and got.get(STATUS, {}).get("type") == "action_msgs/msg/GoalStatusArray"
        and odom.get("count", 0) >= ODOM_HZ * WINDOW * 0.8
        and odom.get("rate_hz") is not None
        and abs(odom["rate_hz"] - ODOM_HZ) <= 0.1 * ODOM_HZ
    )


def watch_odometry(api: str, seconds: float) -> list[tuple[str, float | None, str | None, str | None]]:
    """(state, rate, note, the answer's ``interrupted``) of the odometry, polled for ``seconds``."""
    seen = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        answer = httpx.get(f"{api}/api/topics", timeout=5).json()
        row = next((t for t in answer["topics"] if t["name"] == ODOM), None)
        if row is not None:
            seen.append((row["state"], row["rate_hz"], row["note"], answer["interrupted"]))
        time.sleep(0.1)
    return seen


def test_service_events_and_action_topics_are_measured_beside_the_robots_topics(graph):
    """The monitor died at the first ``pkg/srv/Name_Event`` on the graph, and reported the odometry silent
    from then on (issue 53)."""
    backend = start_backend("--transport", "ros", "--no-sim", "--topics-window", str(WINDOW), timeout=30)
    try:
        assert wait_for(lambda: everything_measured(backend.api), 30), topics(backend.api)
        seen = watch_odometry(backend.api, 3.0)
        assert all(state == "ok" and why is None for state, _, _, why in seen), seen
        assert all(rate is not None and abs(rate - ODOM_HZ) <= 0.1 * ODOM_HZ for _, rate, _, _ in seen), seen
        w = workers(backend.api)
        assert {name: w.get(name, {}).get("state") for name in ROS_WORKERS} == dict.fromkeys(
            ROS_WORKERS, "running"
        ), w
        assert all(w[name]["restarts"] == 0 and w[name]["last_error"] is None for name in ROS_WORKERS), w
        # the same types across the bridge: a rosbridge client reads the calls and the feedback
        ros = roslibpy.Ros("127.0.0.1", backend.bridge_port)
        ros.run(timeout=10)
        try:
            calls: list = []
            feedback: list = []
            roslibpy.Topic(ros, EVENTS, "std_srvs/srv/Trigger_Event").subscribe(calls.append)
            roslibpy.Topic(ros, FEEDBACK, "test_msgs/action/Fibonacci_FeedbackMessage").subscribe(
                feedback.append
            )
            assert wait_for(lambda: len(calls) >= 2 and feedback, 10), (calls, feedback)
            assert {c["info"]["event_type"] for c in calls} & {1, 2}  # REQUEST_RECEIVED, RESPONSE_SENT
            assert feedback[0]["feedback"]["sequence"]  # uint8[16] travels base64, as rosbridge sends it
            assert len(base64.b64decode(feedback[0]["goal_id"]["uuid"])) == 16
        finally:
            ros.close()
    finally:
        assert backend.stop() == 0


def test_each_ros_worker_made_to_fail_restarts_and_the_odometry_is_never_silent(graph):
    """Each worker fails 3 s after it started; the monitor three times more, at once, so that it is down
    through three backoffs (1.4 s and more without a reader's round: a steady 50 Hz topic is silent after
    1 s): its topics are ``unknown``, with the reason, never silent. The executor likewise, later (6 s),
    while a rosbridge client reads the odometry: the topic is then measured on the relay's reader, which
    the executor spins, and is ``unknown`` while it is down, never silent."""
    restarts = {"topic-monitor": 4, "rclpy-executor": 5, "rclpy-provider": 1, "qos-follower": 1}
    after = {name: 6 if name == "rclpy-executor" else 3 for name in ROS_WORKERS}
    faults = ",".join(f"{name}@{after[name]}*{n}" for name, n in restarts.items())
    backend = start_backend(
        "--transport",
        "ros",
        "--no-sim",
        "--topics-window",
        str(WINDOW),
        timeout=30,
        env={"ARBITER_FAULT": faults},
    )
    ros = roslibpy.Ros("127.0.0.1", backend.bridge_port)
    try:
        ros.run(timeout=10)
        odometry: list = []
        roslibpy.Topic(ros, ODOM, "nav_msgs/msg/Odometry").subscribe(odometry.append)  # the relay reads it
        seen = watch_odometry(backend.api, 1.0)  # from before the faults...
        assert wait_for(lambda: odometry, 4), "the relay delivers the odometry before the executor's faults"

        def all_restarted() -> bool:
            seen.extend(watch_odometry(backend.api, 0.3))
            w = workers(backend.api)
            return all(
                w.get(n, {}).get("restarts") == restarts[n] and w[n]["state"] == "running" for n in restarts
            )

        assert wait_for(all_restarted, 30), workers(backend.api)
        seen.extend(watch_odometry(backend.api, WINDOW))  # ...to a whole window after the last
        w = workers(backend.api)
        for name in ROS_WORKERS:
            assert w[name]["last_error"] == {"type": "InjectedFault", "message": f"ARBITER_FAULT={name}"}, w
        # never judged for want of a reader: not silent, nor slow or quiet (the executor's gap, unheld)
        assert not [s for s in seen if s[0] not in ("waiting", "ok", "unknown")], seen
        why = {f"{label} restarted: InjectedFault: ARBITER_FAULT={name}" for label, name in HELD_BY}
        held = [s for s in seen if s[3] is not None]
        assert held and all(s[0] == "unknown" and s[2] == s[3] for s in held), seen
        assert {part for s in held for part in s[3].split("; ")} == why, seen  # by each (together: "; ")
        assert wait_for(lambda: everything_measured(backend.api), 10), topics(backend.api)
        last = watch_odometry(backend.api, 0.2)[-1]
        assert last[:1] + last[2:] == ("ok", None, None), last  # back, and judged again
        assert backend.proc.poll() is None
    finally:
        ros.close()
        assert backend.stop() == 0
    # the error logged once per worker, not a traceback per retry
    err = backend.proc.stderr.read() if backend.proc.stderr else ""
    for name in ROS_WORKERS:
        assert err.count(f"{name} failed, restarting") == 1, err
