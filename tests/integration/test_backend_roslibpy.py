"""End to end: `arbiter-backend` as a subprocess, driven by the real roslibpy client over real sockets."""

import itertools
import json
import math
import socket
import threading
import time

import httpx
import roslibpy

from arbiter_core import envelope

from ..support.backend import get_json, start_backend, wait_for


def connect(port: int) -> roslibpy.Ros:
    ros = roslibpy.Ros("127.0.0.1", port)
    try:
        ros.run(timeout=10)
    except roslibpy.core.RosTimeoutError as exc:
        # Once seen under load in a fresh clone and not reproduced since: say what state things were in
        raise AssertionError(f"roslibpy did not connect in 10 s: {why_not_connected(ros, port)}") from exc
    return ros


def why_not_connected(ros: roslibpy.Ros, port: int) -> str:
    """Evidence for a connect that timed out: does the port accept, how often did roslibpy retry."""
    from twisted.internet import reactor

    try:
        socket.create_connection(("127.0.0.1", port), timeout=2).close()
        accepts = "the port accepts TCP"
    except OSError as exc:
        accepts = f"the port refuses TCP ({exc})"
    f = ros.factory
    return (
        f"{accepts}; reactor running {reactor.running}; factory retries {getattr(f, 'retries', '?')}, "
        f"next delay {float(getattr(f, 'delay', float('nan'))):.3g} s; connector state "
        f"{getattr(f.connector, 'state', None)}; threads {threading.active_count()}"
    )


def command_publisher(ros: roslibpy.Ros) -> roslibpy.Topic:
    """/stamped_cmd_vel advertised. No pause is needed before the first publish: roslibpy writes the
    advertise and the publishes in order on one socket, and the endpoint handles them in order."""
    pub = roslibpy.Topic(ros, "/stamped_cmd_vel", "std_msgs/String")
    pub.advertise()
    return pub


def measured_twists(ros: roslibpy.Ros) -> list:
    """Every Twist on /cmd_vel_measured, appended as it arrives."""
    twists: list = []
    roslibpy.Topic(ros, "/cmd_vel_measured", "geometry_msgs/Twist").subscribe(twists.append)
    return twists


def test_stamped_commands_become_records_twists_and_motion():
    # speed-up limits out of the way: this test follows each command to the robot unchanged
    # (the limits have their own tests below, in real time)
    backend = start_backend("--max-linear-accel", "1000", "--max-angular-accel", "1000")
    driver = connect(backend.bridge_port)
    observer = connect(backend.bridge_port)
    try:
        twists, reports, odom = [], [], []
        roslibpy.Topic(observer, "/cmd_vel_measured", "geometry_msgs/Twist").subscribe(twists.append)
        roslibpy.Topic(observer, "/latency_report", "std_msgs/String").subscribe(
            lambda m: reports.append(json.loads(m["data"]))
        )
        roslibpy.Topic(observer, "/odom", "nav_msgs/Odometry").subscribe(odom.append)
        assert wait_for(lambda: len(odom) > 3)
        start_x = odom[-1]["pose"]["pose"]["position"]["x"]
        pub = roslibpy.Topic(driver, "/stamped_cmd_vel", "std_msgs/String")
        pub.advertise()
        n = 30
        sent = [(0.4 + 0.01 * i, 0.02 * (i % 3)) for i in range(n)]
        for i, (v, w) in enumerate(sent):
            pub.publish(roslibpy.Message({"data": envelope.build(v, w, seq=i)}))
            time.sleep(0.03)
        assert wait_for(lambda: len(reports) >= n)

        body = get_json(f"{backend.api}/api/latency?limit=1000")
        records = body["records"]
        assert len(records) == n and body["stats"]["count"] == n
        assert [r["seq"] for r in records] == list(range(n))
        now = time.time()
        for r, (v, w) in zip(records, sent, strict=True):
            assert set(r) == {
                "latency_ms",
                "linear_x",
                "angular_z",
                "timestamp",
                "deploy_mode",
                "seq",
                "rx_seq",
                "t_recv_ms",
                "t_sent_ms",
            }
            # NTP t1, t2: the tracker's receive and report times (epoch ms); t1 - stamp is the seed's figure
            assert r["t_recv_ms"] <= r["t_sent_ms"] < r["t_recv_ms"] + 1000
            assert abs(r["t_recv_ms"] - r["timestamp"] * 1000) < 0.002  # a float of epoch s: ~0.24 µs
            assert r["rx_seq"] == r["seq"] + 1  # the tracker's own receive counter
            assert (r["linear_x"], r["angular_z"], r["deploy_mode"]) == (v, w, "native")
            assert r["latency_ms"] == round(r["latency_ms"], 4)
            assert 0 <= r["latency_ms"] < 1000  # same host, same clock
            assert now - 30 < r["timestamp"] <= now
        assert [r["seq"] for r in reports[:n]] == list(range(n))

        # the same N twists reached the robot side, in order, then exactly one watchdog zero
        assert wait_for(lambda: len(twists) >= n + 1, timeout=3)
        got = [(t["linear"]["x"], t["angular"]["z"]) for t in twists[:n]]
        assert got == sent
        time.sleep(0.8)  # an absence: no second zero after the watchdog's one (timeout 0.5 s)
        tail = twists[n:]
        assert len(tail) == 1 and tail[0]["linear"]["x"] == 0.0 and tail[0]["angular"]["z"] == 0.0

        # the simulated robot moved forwards (+x, heading ~0) and then stopped
        def pose():
            return odom[-1]["pose"]["pose"]["position"]

        moved = pose()["x"] - start_x
        assert moved > 0.2
        x_after_stop = pose()["x"]
        time.sleep(0.5)  # an absence: the stopped robot does not creep
        assert abs(pose()["x"] - x_after_stop) < 1e-6
        assert odom[-1]["twist"]["twist"]["linear"]["x"] == 0.0
        h = odom[-1]["header"]
        assert h["frame_id"] == "odom" and odom[-1]["child_frame_id"] == "base_link"
        assert set(h["stamp"]) == {"sec", "nanosec"}
        q = odom[-1]["pose"]["pose"]["orientation"]
        assert math.isclose(q["x"] ** 2 + q["y"] ** 2 + q["z"] ** 2 + q["w"] ** 2, 1.0)
    finally:
        driver.close()
        observer.close()
        backend.stop()


def test_bad_envelopes_are_counted_not_forwarded_and_valid_traffic_flows(backend):
    ros = connect(backend.bridge_port)
    try:
        twists = measured_twists(ros)
        pub = command_publisher(ros)
        bad = [
            "not json",
            "[]",
            '{"header": {}}',
            '{"header": {"stamp": "x"}, "twist": {"linear": {"x": 1}, "angular": {"z": 0}}}',
            '{"header": {"stamp": 1}, "twist": {"linear": {"x": NaN}, "angular": {"z": 0}}}',
            "x" * 70_000,
        ]
        for i, text in enumerate(bad):
            pub.publish(roslibpy.Message({"data": text}))
            pub.publish(roslibpy.Message({"data": envelope.build(0.1, 0.0, seq=i)}))
        assert wait_for(lambda: get_json(f"{backend.api}/api/health")["rejected"] == len(bad))
        health = get_json(f"{backend.api}/api/health")
        assert health["records_count"] == len(bad)
        assert health["last_error"].startswith("too_large")
        assert wait_for(lambda: len(twists) >= len(bad))
        assert all(t["linear"]["x"] in (0.1, 0.0) for t in twists)
    finally:
        ros.close()


def test_out_of_limit_velocities_are_clamped_before_the_robot(backend):
    ros = connect(backend.bridge_port)
    try:
        twists = measured_twists(ros)
        pub = command_publisher(ros)
        for i in range(40):
            pub.publish(roslibpy.Message({"data": envelope.build(50.0, -80.0, seq=i)}))
            time.sleep(0.02)
        assert wait_for(lambda: len(twists) >= 40)
        got = [(t["linear"]["x"], t["angular"]["z"]) for t in twists]
        # never beyond the limits; speeding up at most 2 m/s² and 6 rad/s² (one 0.1 s step at most)
        assert all(0 < v <= 1.0 and -2.0 <= w < 0 for v, w in got)
        assert got[0] == (0.2, -0.6) or got[0] == (0.2, -0.6000000000000001)
        for (v0, w0), (v1, w1) in itertools.pairwise(got):
            assert 0 <= v1 - v0 <= 0.2 + 1e-9 and 0 <= w0 - w1 <= 0.6 + 1e-9
        assert got[-1] == (1.0, -2.0)  # reached the limits, in well under the 0.8 s sent
        rec = get_json(f"{backend.api}/api/latency")["records"][-1]
        assert (rec["linear_x"], rec["angular_z"]) == (50.0, -80.0)  # the record keeps what was commanded
    finally:
        ros.close()


def test_rosapi_topics_and_types_through_roslibpy(backend):
    ros = connect(backend.bridge_port)
    try:
        topics = ros.get_topics()
        assert {"/stamped_cmd_vel", "/cmd_vel_measured", "/latency_report", "/odom"} <= set(topics)
        assert ros.get_topic_type("/odom") == "nav_msgs/msg/Odometry"
        assert ros.get_topic_type("/cmd_vel_measured") == "geometry_msgs/msg/Twist"
    finally:
        ros.close()


def test_api_shapes_limits_and_errors(backend):
    base = backend.api
    empty = get_json(f"{base}/api/latency")
    assert empty["stats"] == {
        "count": 0,
        "mean_ms": None,
        "min_ms": None,
        "max_ms": None,
        "p95_ms": None,
        "stddev_ms": None,
    }
    assert empty["records"] == [] and empty["deploy_mode"] == "native"
    health = get_json(f"{base}/api/health")
    assert health["status"] == "ok" and health["node"] == "latency_tracker"
    assert health["records_count"] == 0 and health["uptime_s"] >= 0
    # additive: this host's time sync (whatever this machine has; never an error)
    assert health["time_sync"]["source"] in ("chrony", "timesyncd", "adjtimex", "unknown")
    assert health["time_sync"]["synchronised"] in (True, False, None)
    for path, status in (("/api/latency?limit=abc", 400), ("/api/latency?limit=-1", 400), ("/nope", 404)):
        r = httpx.get(base + path)
        assert r.status_code == status and r.headers["content-type"].startswith("application/json")
        assert r.json()["status"] == status
    r = httpx.post(f"{base}/api/health")
    assert r.status_code == 405 and r.json()["error"]


def test_limit_returns_the_most_recent_records(backend):
    ros = connect(backend.bridge_port)
    try:
        pub = command_publisher(ros)
        for i in range(12):
            pub.publish(roslibpy.Message({"data": envelope.build(0.0, 0.0, seq=i)}))
        assert wait_for(lambda: get_json(f"{backend.api}/api/health")["records_count"] == 12)
        body = get_json(f"{backend.api}/api/latency?limit=5")
        assert [r["seq"] for r in body["records"]] == [7, 8, 9, 10, 11]
        assert body["stats"]["count"] == 12  # stats cover the window, not just the page
        assert get_json(f"{backend.api}/api/latency?limit=0")["records"] == []
    finally:
        ros.close()


def test_measured_type_twist_stamped_in_the_embedded_transport():
    from ..support.backend import start_backend

    backend = start_backend("--measured-type", "twist_stamped", "--no-sim")
    ros = connect(backend.bridge_port)
    try:
        got = []
        roslibpy.Topic(ros, "/cmd_vel_measured", "geometry_msgs/TwistStamped").subscribe(got.append)
        pub = command_publisher(ros)
        pub.publish(roslibpy.Message({"data": envelope.build(0.15, 0.5, seq=1)}))
        assert wait_for(lambda: len(got) >= 1)
        rec = get_json(f"{backend.api}/api/latency")["records"][0]
        msg = got[0]
        assert msg["twist"]["linear"]["x"] == 0.15 and msg["twist"]["angular"]["z"] == 0.5
        stamp = msg["header"]["stamp"]["sec"] + msg["header"]["stamp"]["nanosec"] * 1e-9
        assert abs(stamp - rec["timestamp"]) < 0.5 and msg["header"]["frame_id"] == "base_link"
        assert wait_for(lambda: len(got) >= 2, timeout=2)  # the watchdog zero is stamped too
        assert got[1]["twist"]["linear"]["x"] == 0.0 and got[1]["header"]["stamp"]["sec"] > 0
    finally:
        ros.close()
        backend.stop()


def test_stale_commands_are_reported_but_never_reach_the_robot(backend):
    ros = connect(backend.bridge_port)
    try:
        twists, reports = measured_twists(ros), []
        roslibpy.Topic(ros, "/latency_report", "std_msgs/String").subscribe(
            lambda m: reports.append(json.loads(m["data"]))
        )
        pub = command_publisher(ros)
        second_ago = lambda: time.time_ns() - 1_000_000_000  # noqa: E731
        pub.publish(roslibpy.Message({"data": envelope.build(0.1, 0.0, seq=1)}))
        pub.publish(roslibpy.Message({"data": envelope.build(0.5, 0.5, seq=2, clock_ns=second_ago)}))
        # the same age is fine when the sender knows its clock is a second behind the tracker's
        ok = envelope.build(0.1, 0.0, seq=3, clock_ns=second_ago, offset_ms=1000.0)
        pub.publish(roslibpy.Message({"data": ok}))
        assert wait_for(lambda: len(reports) >= 3)
        assert [r.get("stale", False) for r in reports] == [False, True, False]
        assert wait_for(lambda: len(twists) >= 3)
        time.sleep(0.1)  # an absence: nothing beyond the three twists
        # fresh, then a stop instead of the stale command, then fresh again, speeding up from rest
        got = [(t["linear"]["x"], t["angular"]["z"]) for t in twists[:3]]
        assert got[:2] == [(0.1, 0.0), (0.0, 0.0)]
        assert 0 < got[2][0] <= 0.1 and got[2][1] == 0.0
        health = get_json(f"{backend.api}/api/health")
        assert health["stale"] == 1 and health["max_command_age_ms"] == 300.0
        assert 1000.0 <= health["last_stale_age_ms"] < 1500.0
    finally:
        ros.close()


def test_a_latched_advertise_reaches_clients_that_subscribe_later(backend):
    """rosbridge's ``latch: true`` on advertise: the last message reaches each later subscriber, once;
    a topic advertised without it gives a late subscriber nothing."""
    talker = connect(backend.bridge_port)
    listeners = []
    try:
        status = roslibpy.Topic(talker, "/arbiter_test/status", "std_msgs/String", latch=True)
        status.advertise()
        status.publish(roslibpy.Message({"data": "ready"}))
        plain = roslibpy.Topic(talker, "/arbiter_test/chatter", "std_msgs/String")
        plain.advertise()
        plain.publish(roslibpy.Message({"data": "gone"}))
        received, missed = [], []
        for _ in range(2):
            ros = connect(backend.bridge_port)
            listeners.append(ros)
            got: list[str] = []
            received.append(got)
            roslibpy.Topic(ros, "/arbiter_test/status", "std_msgs/String").subscribe(
                lambda m, got=got: got.append(m["data"])
            )
            roslibpy.Topic(ros, "/arbiter_test/chatter", "std_msgs/String").subscribe(
                lambda m: missed.append(m["data"])
            )
            assert wait_for(lambda got=got: got == ["ready"], 5), got
        # a newer message: once it is in, a second copy of "ready" or anything of the unlatched topic
        # would have come before it (each listener's messages arrive in order on one socket)
        status.publish(roslibpy.Message({"data": "busy"}))
        assert wait_for(lambda: received == [["ready", "busy"], ["ready", "busy"]], 5), received
        assert missed == []
    finally:
        for ros in (talker, *listeners):
            ros.close()
