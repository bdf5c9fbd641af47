"""Polls the backend's ``GET /api/topics`` (same host, port and token as the latency API) into frozen states.

The console polls only while the topics screen is shown, at most every ``PERIOD_S``. The detail pane's plot
draws each topic's rate over the last minute as the backend sampled it (``rate_history``, once a second,
whether or not anyone asked): the console keeps no history of its own, so it pays nothing while the
screen is closed and the plot covers the minute the moment the screen opens.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from arbiter_core.failures import connect_failure, http_failure
from arbiter_core.topicstats import TopicFigures, TopicsError, parse_topics

if TYPE_CHECKING:
    from .tracker_client import TrackerClient

PERIOD_S = 0.5  # 2 Hz: the screen updates at most this often
NO_BACKEND = "client-side simulation (--sim): no backend, so no topics to watch"


@dataclass(frozen=True)
class TopicsState:
    """What the topics screen shows: the last answer, or why there is none."""

    polls: int = 0  # 0: not polled yet
    error: str | None = None
    window_s: float = 0.0
    topics: tuple[TopicFigures, ...] = ()
    skipped: int = 0  # topics in the answer that were not the documented shape
    echo: tuple[str, str] | None = None  # (topic, its latest message as text, or why there is none)
    unavailable: str | None = None  # why there is no backend to ask at all (client-side simulation)
    interrupted: str | None = None  # the backend's topic monitor is down: "monitor restarted: …"

    def rates(self, name: str) -> tuple[float | None, ...]:
        """``name``'s rate once a second over the last minute, oldest first (None: no rate then), as the
        backend sampled it; empty for a topic not in the answer (or a backend that predates it)."""
        return next((t.rate_history for t in self.topics if t.name == name), ())


@dataclass
class TopicsPoller:
    client: TrackerClient
    state: TopicsState = field(default_factory=TopicsState)

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
        self.state = TopicsState(
            polls=polls,
            window_s=answer.window_s,
            topics=answer.topics,
            skipped=answer.skipped,
            interrupted=answer.interrupted,
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
        )
        return self.state
