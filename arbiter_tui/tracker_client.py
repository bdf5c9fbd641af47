"""Polls the tracker's ``GET /api/latency`` with async httpx (the next poll starts after the last ends)."""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import httpx

WINDOW = 120  # latencies kept for the sparkline


@dataclass
class LatencyView:
    """What the latency screen shows: the last good answer, or why there is none."""

    reachable: bool | None = None  # None: not polled yet
    error: str | None = None
    stats: dict[str, Any] = field(default_factory=dict)
    records: list[dict[str, Any]] = field(default_factory=list)
    deploy_mode: str = "?"
    window: deque[float] = field(default_factory=lambda: deque(maxlen=WINDOW))
    polls: int = 0
    failures: int = 0
    stale: int = 0  # commands the tracker dropped as too old (never forwarded)
    rejected: int = 0  # malformed envelopes
    max_command_age_ms: float | None = None
    _last_key: Any = None

    def apply(self, body: Any) -> None:
        if not isinstance(body, dict) or not isinstance(body.get("stats"), dict):
            raise ValueError("unexpected response shape")
        records = body.get("records")
        if not isinstance(records, list):
            raise ValueError("records missing")
        self.stats = body["stats"]
        self.records = [r for r in records if isinstance(r, dict)]
        self.deploy_mode = str(body.get("deploy_mode", "?"))
        # our tracker's extras; a seed tracker has none of them
        self.stale = _count(body.get("stale"))
        self.rejected = _count(body.get("rejected"))
        age = body.get("max_command_age_ms")
        self.max_command_age_ms = (
            float(age) if isinstance(age, (int, float)) and not isinstance(age, bool) else None
        )
        # add only records newer than the last one seen to the rolling window
        new = self.records
        if self._last_key is not None:
            keys = [(r.get("timestamp"), r.get("seq")) for r in self.records]
            if self._last_key in keys:
                new = self.records[keys.index(self._last_key) + 1 :]
        for r in new:
            lat = r.get("latency_ms")
            if isinstance(lat, (int, float)) and not isinstance(lat, bool) and math.isfinite(lat):
                self.window.append(float(lat))
        if self.records:
            last = self.records[-1]
            self._last_key = (last.get("timestamp"), last.get("seq"))
        self.reachable = True
        self.error = None

    def fail(self, error: str) -> None:
        self.reachable = False
        self.error = error
        self.failures += 1


def _count(value: Any) -> int:
    return value if isinstance(value, int) and not isinstance(value, bool) and value >= 0 else 0


class TrackerClient:
    def __init__(
        self, base_url: str, timeout: float = 1.0, limit: int = 50, token: str | None = None
    ) -> None:
        self.base_url = base_url.rstrip("/")
        self.limit = limit
        self.view = LatencyView()
        headers = {} if token is None else {"Authorization": f"Bearer {token}"}
        self._client = httpx.AsyncClient(timeout=timeout, headers=headers)

    async def poll(self) -> LatencyView:
        self.view.polls += 1
        try:
            resp = await self._client.get(f"{self.base_url}/api/latency", params={"limit": self.limit})
            resp.raise_for_status()
            self.view.apply(resp.json())
        except httpx.HTTPStatusError as exc:
            self.view.fail(f"HTTP {exc.response.status_code}")
        except httpx.HTTPError as exc:
            self.view.fail(type(exc).__name__)
        except ValueError as exc:
            self.view.fail(f"bad response: {exc}")
        return self.view

    async def aclose(self) -> None:
        await self._client.aclose()
