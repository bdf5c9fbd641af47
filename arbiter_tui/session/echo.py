"""The topics screen's echo: one topic's latest message as text, through the link's own throttled
subscription (no Textual). Messages arrive on the link's thread; the shell reads ``current``."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable

from arbiter_core.topicstats import TopicFigures

from ..latency.topics_table import echo_refusal, echo_text
from ..link.base import Echoes, Link

WAITING = "waiting for a message ..."


class TopicEcho:
    """At most one topic echoed at a time; ``current`` is ``(topic, text)`` or None."""

    def __init__(self) -> None:
        self._lock = threading.Lock()  # a late message of the last topic must not overwrite this one's
        self._current: tuple[str, str] | None = None
        self._cancel: Callable[[], None] | None = None

    @property
    def current(self) -> tuple[str, str] | None:
        return self._current

    def show(self, link: Link, figures: TopicFigures | None) -> None:
        """Echo the topic ``figures`` describes (None: stop echoing)."""
        if self._cancel is not None:
            with contextlib.suppress(Exception):
                self._cancel()
            self._cancel = None
        with self._lock:
            self._current = None
        if figures is None:
            return
        name = figures.name
        echoes = isinstance(link, Echoes)
        refusal = echo_refusal(figures) or (None if echoes else "not echoed: no rosbridge link")
        if refusal is not None:
            self._current = (name, refusal)
            return
        shown = (name, WAITING)
        with self._lock:
            self._current = shown

        def received(msg: dict[str, object]) -> None:  # the link's thread: a tuple swap, nothing else
            nonlocal shown
            text = echo_text(msg)
            with self._lock:  # still this echo's (a message may come after it was removed)
                if self._current is shown:
                    self._current = shown = (name, text)

        assert isinstance(link, Echoes)  # (refused above otherwise)
        self._cancel = link.echo(name, figures.type, received)
