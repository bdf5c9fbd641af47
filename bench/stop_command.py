#!/usr/bin/env python
"""The command that stops the robot at a mission's end, against the mission's other commands.

Runs the real console (headless, Textual's ``run_test``) on the real backend (a child process, as the
embedded mode starts it), drives ``--missions`` corner missions with go_to_goal at full speed, and
reads the tracker's records: the one-way latency (tracker receive minus the console's stamp, one host,
one clock) of each mission's stop command (the zero that follows its driving commands) beside the p50
of the driving commands. The stop command once arrived 10-20x slower than the others: the run's
summary (numpy) was computed on the control thread just before it, and the UI thread woke for the
mission's end while the link's thread stamped and wrote it. Last line: one JSON object.

    python bench/stop_command.py --missions 5
"""

from __future__ import annotations

import argparse
import asyncio
import itertools
import statistics
import sys
import tempfile
import time
from pathlib import Path

import httpx
from _common import emit

from arbiter_tui.app import make_app
from arbiter_tui.latency.tracker_client import TrackerClient
from arbiter_tui.link.base import CONNECTED
from arbiter_tui.link.embedded import EmbeddedBackend
from arbiter_tui.link.rosbridge import RosLink
from arbiter_tui.settings import Settings


async def _until(pilot, predicate, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        await pilot.pause(0.05)
    return predicate()


async def run(missions: int) -> dict[str, object]:
    backend = EmbeddedBackend.start(bridge_port=0, api_port=0)
    api = f"http://127.0.0.1:{backend.api_port}"
    link = RosLink("127.0.0.1", backend.bridge_port)
    settings = Settings(handle_signals=False, export_dir=Path(tempfile.mkdtemp()), speed=1.0, turn=2.0)
    app = make_app(settings, link, TrackerClient(api))
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            assert await _until(pilot, lambda: link.state == CONNECTED, 15)
            await pilot.press("a")  # go_to_goal
            app.session.select_mission("corner")
            for _ in range(missions):
                await pilot.press("G")  # the mission afresh from where the robot stands
                assert await _until(pilot, lambda: app.loop.running, 5)
                assert await _until(pilot, lambda: not app.loop.running, 60), "the mission did not end"
                await pilot.pause(0.5)
        records = httpx.get(f"{api}/api/latency?limit=1000", timeout=10).json()["records"]
    finally:
        link.close()
        backend.stop()
    records.sort(key=lambda r: r["seq"])
    stops, driving = [], []
    for before, r in itertools.pairwise(records):
        moving = before["linear_x"] != 0.0 or before["angular_z"] != 0.0
        if r["linear_x"] == 0.0 and r["angular_z"] == 0.0 and moving:
            stops.append(r["latency_ms"])
        elif r["linear_x"] != 0.0 or r["angular_z"] != 0.0:
            driving.append(r["latency_ms"])
    p50 = statistics.median(driving)
    return {
        "bench": "stop_command",
        "missions": missions,
        "driving_commands": len(driving),
        "driving_p50_ms": round(p50, 3),
        "stop_ms": [round(s, 3) for s in stops],
        "stop_median_ms": round(statistics.median(stops), 3) if stops else None,
        "stop_over_driving_p50": round(statistics.median(stops) / p50, 1) if stops else None,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--missions", type=int, default=5)
    args = parser.parse_args(argv)
    result = asyncio.run(run(args.missions))
    print(
        f"driving commands p50 {result['driving_p50_ms']} ms ({result['driving_commands']}); "
        f"stop commands {result['stop_ms']} ms: median {result['stop_over_driving_p50']}x the p50"
    )
    emit(result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
