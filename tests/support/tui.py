"""Test doubles at the link boundary and a deterministic app builder for snapshot and Pilot tests."""

import time

from arbiter_core.kinematics import Pose
from arbiter_core.record import LatencyRecord
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.app import make_app
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED, Telemetry
from arbiter_tui.settings import Settings

from .points import make_point


class FakeClock:
    def __init__(self, t: float = 1000.0):
        self.t = t

    def __call__(self) -> float:
        return self.t


class RecordingLink:
    """Stands in for the rosbridge link where a test must see exactly what would go on the wire."""

    def __init__(self, state: str = CONNECTED):
        self.telemetry = Telemetry()
        self._state = state
        self.sent: list[tuple[float, float]] = []

    @property
    def state(self) -> str:
        return self._state

    def send(self, v: float, w: float) -> bool:
        if self._state != CONNECTED:
            return False
        self.sent.append((v, w))
        return True

    def close(self) -> None:
        pass


def still_app(tmp_path=None, link=None, store=None, tracker_view=True, mode="embedded"):
    """An app with no timers, seeded data and a fixed pose: every frame is the same."""
    settings = Settings(mode=mode, live=False, handle_signals=False, export_dir=tmp_path or ".")
    link = link or RecordingLink()
    link.telemetry.pose = Pose(1.25, -0.5, 0.6)
    link.telemetry.v, link.telemetry.w = 0.4, 0.2
    link.telemetry.latency_ms = 0.42
    meter = link.telemetry.meter
    for i in range(20):  # round trips to a tracker whose clock runs 12 ms ahead: the warning shows
        stamp = 1_800_000_000_000.0 + 10.0 * i
        meter.on_send(i, stamp, 50.0 + i)
        raw = 12.0 + 0.2 + 0.01 * (i % 5)
        record = LatencyRecord(raw, 0.0, 0.0, (stamp + raw) / 1000.0, "native", seq=i)
        meter.on_report(record, 50.0 + i + 0.0005 + i * 1e-5)
    if store is None:
        store = AnalyticsStore()
        store.start_collection()
        for i in range(120):
            store.record(make_point(i, ("manual", "go_to_goal", "pure_pursuit")[i // 40]))
        store.stop_collection()
    tracker = None
    if mode != "sim":
        tracker = TrackerClient("http://127.0.0.1:9")
        if tracker_view:
            tracker.view.apply(
                {
                    "stats": {
                        "count": 3,
                        "mean_ms": 0.31,
                        "min_ms": 0.2,
                        "max_ms": 0.45,
                        "p95_ms": 0.45,
                        "stddev_ms": 0.1,
                    },
                    "records": [
                        {
                            "latency_ms": 0.2 + 0.1 * i,
                            "linear_x": 0.5,
                            "angular_z": 0.0,
                            "timestamp": 1.0 + i,
                            "deploy_mode": "native",
                            "seq": i,
                        }
                        for i in range(3)
                    ],
                    "deploy_mode": "native",
                }
            )
    clock = FakeClock()
    app = make_app(settings, link, tracker, store=store, clock=clock)
    app.fake_clock = clock
    for _ in range(30):
        app.loop.add_trail(0.05 * _, 0.01 * _ * _ / 10)
    return app


async def until(pilot, predicate, timeout: float = 8.0, step: float = 0.02) -> bool:
    """Let the app run until ``predicate()`` holds (True) or ``timeout`` passes (its last value)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        await pilot.pause(step)
    return predicate()
