"""``arbiter-tui topics``: the backend's topic figures once, headless, for scripts and CI.

``--expect '/scan>=9.5,/odom>=45'`` exits 1 when a topic is below its rate (or absent), with one line
per reason on stderr; 2 on bad arguments; 3 when the backend cannot be asked.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys

from arbiter_core.auth import AuthConfigError
from arbiter_core.cliargs import OneLineParser
from arbiter_core.topicstats import Expectation, TopicsAnswer, parse_expect, unmet
from arbiter_core.urls import UrlError

from ..latency.topics_client import TopicsPoller
from ..latency.topics_table import COLUMNS, aligned, cells
from ..latency.tracker_client import TrackerClient
from . import tracker_args


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="arbiter-tui topics",
        description="Print the rate, bandwidth, delay and age of every topic the backend measures "
        "(GET /api/topics), once.",
    )
    tracker_args.add(p)
    p.add_argument("--json", action="store_true", help="print the answer as JSON (the API's own shape)")
    p.add_argument(
        "--expect",
        metavar="TOPIC>=HZ,...",
        help="exit 1 unless each topic is at or above its rate, e.g. '/scan>=9.5,/odom>=45' (one line per "
        "topic that is not, on stderr)",
    )
    p.add_argument(
        "--wait",
        type=float,
        default=0.0,
        metavar="S",
        help="with --expect: ask again until every expectation is met or S seconds passed (a robot that "
        "is still starting)",
    )
    return p


def table(answer: TopicsAnswer) -> str:
    rows = [COLUMNS, *(cells(t) for t in answer.topics)]
    widths = [max(len(r[i]) for r in rows) for i in range(len(COLUMNS))]
    lines = []
    for r in rows:
        lines.append("  ".join(aligned(v, w, c) for v, w, c in zip(r, widths, COLUMNS, strict=True)))
    lines.append(f"(window {answer.window_s:g} s; {len(answer.topics)} topics)")
    if answer.interrupted:
        lines.append(f"({answer.interrupted}: the states are unknown until it is back)")
    return "\n".join(line.rstrip() for line in lines)


async def _ask(
    client: TrackerClient, expect: list[Expectation] | None, wait: float
) -> tuple[TopicsAnswer | None, str | None]:
    poller = TopicsPoller(client)
    loop = asyncio.get_running_loop()
    deadline = loop.time() + wait
    while True:
        state = await poller.poll()
        answer = (
            TopicsAnswer(state.window_s, state.topics, state.skipped, state.interrupted)
            if state.error is None
            else None
        )
        done = answer is not None and (not expect or not unmet(expect, answer))
        if done or loop.time() >= deadline:
            return answer, state.error
        await asyncio.sleep(0.5)


def run(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    try:
        expect = parse_expect(args.expect) if args.expect is not None else None
        endpoint, token = (tracker := tracker_args.checked(args)).endpoint, tracker.token
    except (ValueError, AuthConfigError, UrlError) as exc:
        print(f"arbiter-tui topics: {exc}", file=sys.stderr)
        return 2

    async def main() -> tuple[TopicsAnswer | None, str | None]:
        client = TrackerClient(endpoint.url, timeout=args.timeout, token=token, ca_file=args.ca_file)
        try:
            return await _ask(client, expect, max(0.0, args.wait))
        finally:
            await client.aclose()

    answer, error = asyncio.run(main())
    if answer is None:
        print(f"arbiter-tui topics: {endpoint.url.rstrip('/')}/api/topics: {error}", file=sys.stderr)
        return 3
    if args.json:
        print(json.dumps({"window_s": answer.window_s, "topics": [t.to_json() for t in answer.topics]}))
    else:
        print(table(answer))
    reasons = unmet(expect, answer) if expect else []
    for reason in reasons:
        print(f"arbiter-tui topics: {reason}", file=sys.stderr)
    return 1 if reasons else 0
