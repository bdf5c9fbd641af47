"""Polls the tracker's ``GET /api/latency`` with async httpx (the next poll starts after the last ends).

Against our tracker the poller pages by ``rx_seq``: each poll asks only for what arrived since the
last one (``?since=``), so a record is never fetched twice. A tracker without ``rx_seq`` (the
seed's own) is polled by ``limit``, and records newer than the last timestamp seen are added.
"""

from __future__ import annotations

import ssl
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from arbiter_core.failures import connect_failure, http_failure
from arbiter_core.hostclock import HostClock
from arbiter_core.record import LatencyRecord, RecordError, parse_latency_stats
from arbiter_core.stats import Summary
from arbiter_core.timesync import TimeSync

from .autonomy_client import AutonomyClient

if TYPE_CHECKING:
    import httpx

WINDOW = 600  # latencies kept for the plot and the histogram
PAGE = 120  # records asked for per poll (a tracker started with a small --max-records refuses more)
RECENT = 50  # records kept for the table
SYNC_EVERY = 20  # polls between reads of both hosts' time sync (/api/health's time_sync, our own)


@dataclass(frozen=True, slots=True)
class TrackerAnswer:
    """What the tracker last said, by value: each poll hands one to whoever shows it (the frame sampler),
    so nothing on the screen reads the poller's own state while it changes."""

    reachable: bool | None = None  # None: not polled yet
    error: str | None = None
    stats: Summary | None = None
    stats_error: str | None = None
    records: tuple[LatencyRecord, ...] = ()  # oldest first
    deploy_mode: str = "?"
    window: tuple[float, ...] = ()
    window_t: tuple[float, ...] = ()  # receive times, epoch s
    failures: int = 0
    stale: int = 0
    rejected: int = 0
    max_command_age_ms: float | None = None
    version: int = 0
    robot_sync: TimeSync | None = None
    local_sync: TimeSync | None = None


@dataclass
class LatencyView:
    """The poller's running state: the last good answer, or why there is none, and where the next poll
    starts. Handed on as a :class:`TrackerAnswer` (``answer``)."""

    reachable: bool | None = None  # None: not polled yet
    error: str | None = None
    stats: Summary | None = None  # over every record the tracker keeps; None: not answered, or malformed
    stats_error: str | None = None  # why the last stats block was not one (its records were still taken)
    records: deque[LatencyRecord] = field(default_factory=lambda: deque(maxlen=RECENT))  # oldest first
    deploy_mode: str = "?"
    window: deque[float] = field(default_factory=lambda: deque(maxlen=WINDOW))
    window_t: deque[float] = field(default_factory=lambda: deque(maxlen=WINDOW))  # receive times, epoch s
    polls: int = 0
    failures: int = 0
    stale: int = 0  # commands the tracker dropped as too old (never forwarded)
    rejected: int = 0  # malformed envelopes
    bad_records: int = 0  # records in an answer that were not the seed's shape (skipped)
    max_command_age_ms: float | None = None
    last_rx_seq: int | None = None  # the newest rx_seq taken in; None: start from the newest records
    pages_by_rx_seq: bool = False  # the tracker answers ``since`` (ours does, the seed's does not)
    version: int = 0  # bumped whenever records or the window change
    robot_sync: TimeSync | None = None  # the tracker host's clock sync (/api/health); None: not said
    local_sync: TimeSync | None = None  # this console's host
    _last_timestamp: float | None = None  # without rx_seq: the newest record taken in

    def answer(self) -> TrackerAnswer:
        return TrackerAnswer(
            reachable=self.reachable, error=self.error, stats=self.stats, stats_error=self.stats_error,
            records=tuple(self.records), deploy_mode=self.deploy_mode, window=tuple(self.window),
            window_t=tuple(self.window_t), failures=self.failures, stale=self.stale, rejected=self.rejected,
            max_command_age_ms=self.max_command_age_ms, version=self.version, robot_sync=self.robot_sync,
            local_sync=self.local_sync,
        )  # fmt: skip

    def params(self, limit: int) -> dict[str, int]:
        """The query for the next poll."""
        if self.pages_by_rx_seq and self.last_rx_seq is not None:
            return {"since": self.last_rx_seq, "limit": max(limit, PAGE)}
        return {"limit": limit}

    def apply(self, body: Any) -> None:
        if not isinstance(body, dict) or not isinstance(body.get("stats"), dict):
            raise ValueError("unexpected response shape")
        try:
            stats: Summary | None = parse_latency_stats(body["stats"])
            self.stats_error = None
        except RecordError as exc:  # the records are still good: keep them, say the block was not
            stats, self.stats_error = None, str(exc)
        raw = body.get("records")
        if not isinstance(raw, list):
            raise ValueError("records missing")
        records = []
        for obj in raw:
            try:
                records.append(LatencyRecord.from_obj(obj))
            except RecordError:
                self.bad_records += 1
        self.stats = stats
        self.deploy_mode = str(body.get("deploy_mode", "?"))
        # our tracker's extras; a seed tracker has none of them
        self.stale = _count(body.get("stale"))
        self.rejected = _count(body.get("rejected"))
        age = body.get("max_command_age_ms")
        self.max_command_age_ms = (
            float(age) if isinstance(age, (int, float)) and not isinstance(age, bool) else None
        )
        head = body.get("last_rx_seq")
        if isinstance(head, int) and not isinstance(head, bool) and head >= 0:
            new = self._take_by_rx_seq(records, head, more=body.get("more") is True)
        else:
            self.pages_by_rx_seq = False
            new = [r for r in records if self._last_timestamp is None or r.timestamp > self._last_timestamp]
            if new:
                self._last_timestamp = new[-1].timestamp
        if new:
            self.records.extend(new)
            self.window.extend(r.latency_ms for r in new)
            self.window_t.extend(r.timestamp for r in new)
            self.version += 1
        self.reachable = True
        self.error = None

    def _take_by_rx_seq(self, records: list[LatencyRecord], head: int, more: bool) -> list[LatencyRecord]:
        self.pages_by_rx_seq = True
        if self.last_rx_seq is not None and head < self.last_rx_seq:
            # the tracker restarted and counts from 1 again: start over from its newest records
            self.last_rx_seq = None
            return []
        seen = self.last_rx_seq or 0
        new = [r for r in records if r.rx_seq is not None and r.rx_seq > seen]
        if new:
            seen = max(r.rx_seq or 0 for r in new)
        elif self.last_rx_seq is None:
            seen = head  # nothing to take in yet: carry on from the tracker's newest
        if more:  # further behind than one page: what lies between would only scroll past
            seen = max(seen, head - PAGE)
        self.last_rx_seq = seen
        return new

    def fail(self, error: str) -> None:
        self.reachable = False
        self.error = error
        self.failures += 1


def _chain(exc: BaseException) -> str:
    """The exception and its causes in one line: httpx says "All connection attempts failed" and keeps
    the useful part (ConnectionRefusedError, a DNS or TLS error) further down the chain."""
    parts, seen = [], 0
    current: BaseException | None = exc
    while current is not None and seen < 6:
        parts.append(f"{type(current).__name__}: {current}")
        current, seen = current.__cause__ or current.__context__, seen + 1
    return " | ".join(parts)


def _count(value: Any) -> int:
    return value if isinstance(value, int) and not isinstance(value, bool) and value >= 0 else 0


class TrackerClient:
    def __init__(
        self,
        base_url: str,
        timeout: float = 1.0,
        limit: int = 50,
        token: str | None = None,
        ca_file: Path | None = None,
    ) -> None:
        self.base_url = base_url.rstrip("/")
        self.limit = limit
        self._token, self._ca_file = token, ca_file
        self.view = LatencyView()
        import httpx  # here, not at module level: ~90 ms the console's first frame need not wait for

        headers = {} if token is None else {"Authorization": f"Bearer {token}"}
        # https:// is verified against the system's CAs, or against --ca-file (a private CA)
        verify: Any = True if ca_file is None else ssl.create_default_context(cafile=str(ca_file))
        self._client: httpx.AsyncClient = httpx.AsyncClient(timeout=timeout, headers=headers, verify=verify)
        self.host_clock = HostClock()

    async def poll(self) -> TrackerAnswer:
        import httpx

        self.view.polls += 1
        try:
            resp = await self._client.get(f"{self.base_url}/api/latency", params=self.view.params(self.limit))
            resp.raise_for_status()
            self.view.apply(resp.json())
        except httpx.HTTPStatusError as exc:
            self.view.fail(http_failure(exc.response.status_code))
        except httpx.TimeoutException:
            self.view.fail("timed out")
        except httpx.HTTPError as exc:
            self.view.fail(connect_failure(type(exc).__name__, _chain(exc)))
        except ValueError as exc:
            self.view.fail(f"bad response: {exc}")
        if self.view.reachable and self.view.polls % SYNC_EVERY == 1:
            await self.poll_time_sync()
        return self.view.answer()

    async def poll_time_sync(self) -> None:
        """Both hosts' clock sync: the tracker's from ``/api/health`` (an older backend says nothing),
        ours from the same probes, off the event loop."""
        import asyncio

        import httpx

        try:
            resp = await self._client.get(f"{self.base_url}/api/health")
            body = resp.json() if resp.status_code == 200 else None
            robot = TimeSync.from_obj(body.get("time_sync")) if isinstance(body, dict) else None
        except (httpx.HTTPError, ValueError):
            robot = self.view.robot_sync
        local = await asyncio.to_thread(self.host_clock.read)
        if (robot, local) != (self.view.robot_sync, self.view.local_sync):
            self.view.robot_sync, self.view.local_sync = robot, local
            self.view.version += 1

    async def get(self, path: str) -> httpx.Response:
        """Another endpoint of the same API (``/api/topics``), with the same client, token and TLS."""
        return await self._client.get(f"{self.base_url}{path}")

    def autonomy(self) -> AutonomyClient:
        """The same backend's robot-side controller API, with the same token and TLS settings."""
        return AutonomyClient(self.base_url, token=self._token, ca_file=self._ca_file)

    async def aclose(self) -> None:
        await self._client.aclose()
