"""Test doubles at the link boundary and a deterministic app builder for snapshot and Pilot tests."""

import time
from dataclasses import replace

from arbiter_core.kinematics import Pose
from arbiter_core.record import LatencyRecord
from arbiter_tui.analytics.store import AnalyticsStore
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED, Telemetry
from arbiter_tui.session.settings import Settings
from arbiter_tui.shell.app import make_app
from arbiter_tui.shell.screens.base import BaseScreen

SEEDED_POINTS = 300  # the seeded store's ring: smaller than its runs, so it has dropped samples of run 1


def seeded_store(latency_ms=None) -> AnalyticsStore:
    """Runs as the console records them, driven in simulated time (deterministic): go_to_goal completes
    the square, pure_pursuit is stopped half-way round the figure eight; the ring (300) has dropped the
    oldest samples of run 1, so the analytics screen warns. ``latency_ms(i)``: the i-th sample's
    one-way latency (default: none measured, as over a simulated link)."""
    from dataclasses import replace

    from arbiter_core.controllers import MISSIONS
    from arbiter_tui.analytics.runs import ABORTED, COMPLETED
    from arbiter_tui.analytics.tracking import reference_path
    from arbiter_tui.session.compare import run_one

    store = AnalyticsStore(max_data_points=SEEDED_POINTS)
    store.start_collection()
    t0 = 1_800_000_000_000.0
    for algorithm, mission, keep in (("go_to_goal", "square", None), ("pure_pursuit", "figure_eight", 150)):
        result = run_one(algorithm, mission)
        points = result.points[:keep]
        path = reference_path((0.0, 0.0), MISSIONS[mission])  # as the console's loop gives it
        run = store.begin_run(algorithm, mission, t0 + points[0].timestamp - 100, path)
        for p in points:
            lat = None if latency_ms is None else latency_ms(len(store))
            store.record(replace(p, timestamp=t0 + p.timestamp, runId=run, latencyMs=lat))
        done = keep is None and result.completed
        store.end_run(COMPLETED if done else ABORTED, t0 + points[-1].timestamp,
                      result.final_error_m if done else 0.8)  # fmt: skip
        t0 += points[-1].timestamp + 1000
    store.stop_collection()
    return store


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


def still_app(tmp_path=None, link=None, store=None, tracker_view=True, mode="embedded", **more):
    """An app with no timers, seeded data and a fixed pose: every frame is the same. ``more``: other
    settings (observe mode...)."""
    settings = Settings(mode=mode, live=False, handle_signals=False, export_dir=tmp_path or ".", **more)
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
        store = seeded_store()
    settings.max_points = store.max_data_points  # the app would resize the ring to its setting
    tracker = None
    if mode != "sim":
        tracker = TrackerClient("http://127.0.0.1:9")
        if tracker_view:
            tracker.view.apply(
                {
                    "stats": {
                        "count": 60,
                        "mean_ms": 0.31,
                        "min_ms": 0.2,
                        "max_ms": 0.45,
                        "p95_ms": 0.45,
                        "stddev_ms": 0.1,
                    },
                    "records": [
                        {
                            "latency_ms": round(0.3 + 0.05 * (i % 7) + (1.5 if i % 23 == 0 else 0.0), 3),
                            "linear_x": 0.5,
                            "angular_z": 0.0,
                            "timestamp": 1.0 + i,
                            "deploy_mode": "native",
                            "seq": i,
                        }
                        for i in range(60)
                    ],
                    "deploy_mode": "native",
                }
            )
    clock = FakeClock()
    app = make_app(settings, link, tracker, store=store, clock=clock)
    if tracker is not None:
        app.sampler.latency_polled(tracker.view.answer())  # as the poller hands it on
    app.fake_clock = clock
    for _ in range(30):
        app.session.loop.trail.add(0.05 * _, 0.01 * _ * _ / 10)
    return app


async def until(pilot, predicate, timeout: float = 8.0, step: float = 0.02) -> bool:
    """Let the app run until ``predicate()`` holds (True) or ``timeout`` passes (its last value)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        await pilot.pause(step)
    return predicate()


def show_frame(app, **parts) -> None:
    """Put ``parts`` (fields of ``Frame``) on screen as they are, without sampling: data the session
    cannot make on its own (a backend's answer, a sweep's curve, a run the ring dropped)."""
    frame = app.sampler.frame = replace(app.sampler.frame, **parts)
    for screen in app.screen_stack:
        if isinstance(screen, BaseScreen):
            screen.frame = frame


def burst(app, *keys: str) -> None:
    """``keys`` (names, as Pilot's ``press`` takes them) typed in one burst, as Textual's terminal driver
    delivers them: parsed on its input thread, through ``direct_keys`` (the headless driver here), then
    queued for the app, all before the app answers the first. Pilot's ``press`` waits for each key's
    answer before the next; a user's fingers do not."""
    import threading

    from textual import events
    from textual.drivers.headless_driver import HeadlessDriver
    from textual.keys import key_to_character

    from arbiter_tui.shell.keys import direct_keys

    driver = direct_keys(HeadlessDriver, lambda: app.keys)(app)

    def deliver() -> None:
        for key in keys:
            driver.process_message(events.Key(key, key_to_character(key)))

    thread = threading.Thread(target=deliver)
    thread.start()
    thread.join()


def tracker_said(app) -> None:
    """The tracker view a test changed, handed to the screens as the poller hands its answers on."""
    app.sampler.latency_polled(app.tracker.view.answer())


def screen_text(app) -> str:
    """What the terminal shows now, as text: the screen in front over the screens it lets show through
    (a dialog over the screen behind it), as Textual composes them for the terminal."""
    from textual._context import visible_screen_stack

    visible_screen_stack.set(app._background_screens)
    return "\n".join(strip.text.rstrip() for strip in app.screen._compositor.render_strips())
