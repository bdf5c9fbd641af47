"""Runs inside the robot's network namespace (``ip netns exec``): a roslibpy client of the console's
embedded backend, which binds 127.0.0.1 there. Prints one JSON line per message, stamped with
``time.monotonic()`` (one clock for every network namespace: the host's sender compares with it):

    {"t": ..., "k": "cmd", "v": 0.5, "w": 0.0}      # /cmd_vel_measured (what the tracker forwarded)
    {"t": ..., "k": "odom", "x": ..., "y": ...}     # /odom

``python -m tests.support.sshlink_probe PORT``; it retries until the backend answers (the console
starts it when the SSH session starts), and says ``{"k": "up"}`` once subscribed.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from typing import Any

import roslibpy

_out = threading.Lock()


def emit(obj: dict[str, Any]) -> None:
    with _out:
        sys.stdout.write(json.dumps(obj) + "\n")
        sys.stdout.flush()


def main(port: int) -> None:
    while True:
        ros = roslibpy.Ros(host="127.0.0.1", port=port)
        try:
            ros.run(timeout=2)
            break
        except Exception:
            ros.close()
            time.sleep(0.3)

    def on_cmd(m: dict[str, Any]) -> None:
        emit({"t": time.monotonic(), "k": "cmd", "v": m["linear"]["x"], "w": m["angular"]["z"]})

    def on_odom(m: dict[str, Any]) -> None:
        p = m["pose"]["pose"]["position"]
        emit({"t": time.monotonic(), "k": "odom", "x": p["x"], "y": p["y"]})

    roslibpy.Topic(ros, "/cmd_vel_measured", "geometry_msgs/Twist").subscribe(on_cmd)
    roslibpy.Topic(ros, "/odom", "nav_msgs/Odometry").subscribe(on_odom)
    emit({"t": time.monotonic(), "k": "up"})
    while True:
        time.sleep(3600)


if __name__ == "__main__":
    main(int(sys.argv[1]))
