"""Polls the backend's ``GET /api/topics`` (same host, port and token as the latency API) into frozen states.

The console polls only while the topics screen is shown, at most every ``PERIOD_S``; each topic's rate
is remembered over the last ``HISTORY`` polls for the detail pane's plot.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from arbiter_core.failures import connect_failure, http_failure
from arbiter_core.topicstats import TopicFigures, TopicsError, parse_topics

if TYPE_CHECKING:
    from .tracker_client import TrackerClient

PERIOD_S = 0.5  # 2 Hz: the screen updates at most this often
HISTORY = 120  # polls of each topic's rate kept: a minute at 2 Hz


@dataclass(frozen=True)
class TopicsState:
    """What the topics screen shows: the last answer, or why there is none."""

    polls: int = 0  # 0: not polled yet
    error: str | None = None
    window_s: float = 0.0
    topics: tuple[TopicFigures, ...] = ()
    skipped: int = 0  # topics in the answer that were not the documented shape
    # per topic, its rate at each of the last polls (None: no rate then), oldest first
    history: tuple[tuple[str, tuple[float | None, ...]], ...] = ()
    echo: tuple[str, str] | None = None  # (topic, its latest message as text, or why there is none)

    def rates(self, name: str) -> tuple[float | None, ...]:
        return next((h for n, h in self.history if n == name), ())


@dataclass
class TopicsPoller:
    client: TrackerClient
    state: TopicsState = field(default_factory=TopicsState)
    _history: dict[str, deque[float | None]] = field(default_factory=dict)

    async def poll(self) -> TopicsState:
        import httpx

        polls = self.state.polls + 1
        try:
            resp = await self.client.get("/api/topics")
            resp.raise_for_status()
            answer = parse_topics(resp.json())
        except httpx.HTTPStatusError as exc:
            return self._failed(polls, http_failure(exc.response.status_code))
        except httpx.TimeoutException:
            return self._failed(polls, "timed out")
        except httpx.HTTPError as exc:
            return self._failed(polls, connect_failure(type(exc).__name__, str(exc)))
        except (ValueError, TopicsError) as exc:
            return self._failed(polls, f"bad response: {exc}")
        names = {t.name for t in answer.topics}
        for gone in set(self._history) - names:
            del self._history[gone]
        for t in answer.topics:
            self._history.setdefault(t.name, deque(maxlen=HISTORY)).append(t.rate_hz)
        self.state = TopicsState(
            polls=polls,
            window_s=answer.window_s,
            topics=answer.topics,
            skipped=answer.skipped,
            history=tuple((n, tuple(h)) for n, h in sorted(self._history.items())),
        )
        return self.state

    def _failed(self, polls: int, error: str) -> TopicsState:
        """Keep the last figures (marked by the error) so the screen does not go blank on one bad poll."""
        self.state = TopicsState(
            polls=polls,
            error=error,
            window_s=self.state.window_s,
            topics=self.state.topics,
            skipped=self.state.skipped,
            history=self.state.history,
        )
        return self.state
