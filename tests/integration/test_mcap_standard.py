"""The MCAP export's standard channel is the real nav_msgs/msg/Odometry: its bytes deserialise with ROS 2's
own type support (rclpy), so Foxglove, PlotJuggler and `ros2 bag` read it without our message types."""

import io
import math

from arbiter_tui.analytics.exports import MCAP_ODOM_TOPIC, MCAP_RUNS_TOPIC, to_mcap
from arbiter_tui.analytics.store import AnalyticsStore

from ..support.points import make_point
from ..support.ros import Odometry


def test_odometry_channel_deserialises_as_ros2_nav_msgs_odometry():
    from mcap.reader import make_reader
    from rclpy.serialization import deserialize_message

    store = AnalyticsStore()
    store.start_collection()
    run = store.begin_run("go_to_goal", "square", 1_700_000_000_000.0)
    pts = [make_point(i, "go_to_goal", run=run) for i in range(12)]
    for p in pts:
        store.record(p)
    store.end_run("completed", pts[-1].timestamp, 0.1)
    data = to_mcap(store.points(), store.stats(), store.runs())
    reader = make_reader(io.BytesIO(data))
    schemas = {
        c.topic: reader.get_summary().schemas[c.schema_id] for c in reader.get_summary().channels.values()
    }
    assert schemas[MCAP_ODOM_TOPIC].name == "nav_msgs/msg/Odometry"
    assert schemas[MCAP_ODOM_TOPIC].encoding == "ros2msg"
    odoms = [m for _s, c, m in reader.iter_messages(topics=[MCAP_ODOM_TOPIC])]
    assert len(odoms) == len(pts)
    for p, m in zip(pts, odoms, strict=True):
        msg = deserialize_message(m.data, Odometry)  # ROS 2's own CDR reader for the real type
        assert msg.header.frame_id == "odom" and msg.child_frame_id == "base_link"
        assert msg.pose.pose.position.x == p.x and msg.pose.pose.position.y == p.y
        q = msg.pose.pose.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        assert math.isclose(yaw, p.theta, abs_tol=1e-9)
        assert msg.twist.twist.linear.x == p.linearVel and msg.twist.twist.angular.z == p.angularVel
        assert msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec == m.log_time
    runs = list(reader.iter_messages(topics=[MCAP_RUNS_TOPIC]))
    assert len(runs) == 1
