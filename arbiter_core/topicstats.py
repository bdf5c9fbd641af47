"""Is every topic alive: rate, bandwidth, delay and age of each topic, over a sliding window. Pure.

The backend feeds one :class:`TopicWindow` per topic with (receive time, size in bytes, header delay)
per message and answers ``GET /api/topics`` with :meth:`TopicWindow.figures`; the console parses the
answer with :func:`parse_topics` into frozen :class:`TopicFigures`. One definition of each figure:

- rate: ``(n - 1) / (t_last - t_first)`` over the ``n`` messages received in the window (as
  ``ros2 topic hz``: the reciprocal of the mean period), with the period's min / max / std;
- bandwidth: the window's bytes over the time they span, ``sum(size) / (t_last - t_first) * (n - 1) / n``
  (for a steady publisher this is mean size x rate, as ``ros2 topic bw`` reports it), and the mean size;
- delay: receive wall time - ``header.stamp`` of each stamped message (as ``ros2 topic delay``), mean
  and p95;
- age: now - the last message's receive time, kept when the window is empty (a topic silent for a
  minute is a minute old);
- rate history: the rate, once a second (``sample``, which the backend calls whether or not anyone asks),
  over the last ``RATE_HISTORY`` seconds, so the console can plot the last minute the moment it opens;
- state: ``waiting`` (never a message), ``silent`` (a steady topic that stopped, see below), ``quiet``
  (nothing in the window, and not ``silent``: a topic that publishes on demand), ``slow`` (the rate fell
  below ``SLOW_FRACTION`` of the usual rate: the highest rate seen, decaying with a half-life of
  ``USUAL_HALF_LIFE_S``, so a topic that settles at a new rate is usual again a minute later), else
  ``ok``; ``unmeasured`` when the backend cannot subscribe (its type is not installed there, or it
  cannot be read: the note says why); ``unknown`` while the monitor that measures it is restarting or
  failed (the note, and the answer's ``interrupted``, say "monitor restarted: …"): not ``silent``.

Stopped or quiet: a sensor that stops is a fault, a command topic that stops is a robot standing still.
Each topic's rhythm is followed message by message: its period and the period's spread, averaged over
about a window of time. It is **steady** when its periods are regular (spread at most ``REGULAR_CV`` of
the period, over at least ``MIN_GAPS`` periods) and it has published that way, with no pause, for a
whole window, and either since it first published (it did not wait a window or more for its first
message and never paused) or for ``STEADY_S``. A pause is a gap of ``STOP_PERIODS`` of its periods and
at least ``STOP_MIN_S`` (a window, while its period is not known yet). A steady topic that then misses
``STOP_PERIODS`` of its periods (at least ``STOP_MIN_S``) is ``silent``; any other topic with nothing in
the window is ``quiet``: it has shown it publishes on demand (commands, events, logs) or in bursts.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from dataclasses import dataclass
from typing import Any

from .stats import percentile

WINDOW_S = 5.0  # the sliding window: long enough for a 1 Hz topic's rate, short enough to see it stop
MAX_SAMPLES = 20_000  # per topic: a 4 kHz topic fills the window; beyond, the oldest go first
SLOW_FRACTION = 0.7
USUAL_HALF_LIFE_S = 60.0
NOT_INSTALLED = "type not installed here"
CANNOT_READ = "cannot be read here"  # the start of the note of a topic the monitor could not look at
# stopped or quiet (see the module's docstring)
REGULAR_CV = 0.5  # periods are regular when their standard deviation is at most half their mean
MIN_GAPS = 5  # periods seen before a rhythm is judged
STOP_PERIODS = 5.0  # a steady topic has stopped after missing this many of its periods...
STOP_MIN_S = 1.0  # ...and at least this long: a hiccup is not a stop
STEADY_S = 60.0  # a topic that waited or paused before is steady after publishing regularly this long
SAMPLE_S = 1.0  # the rate history: one sample a second...
RATE_HISTORY = 60  # ...over the last minute

STATES = ("ok", "slow", "silent", "quiet", "waiting", "unmeasured", "unknown")


class TopicsError(ValueError):
    """A ``/api/topics`` answer that is not the documented shape."""


@dataclass(frozen=True)
class TopicFigures:
    """One topic's figures over the window (times in ms, rates in Hz, sizes in bytes)."""

    name: str
    type: str
    state: str
    publishers: int = 0
    subscribers: int = 0
    count: int = 0  # messages in the window
    total: int = 0  # messages since the topic was first watched
    rate_hz: float | None = None
    period_min_ms: float | None = None
    period_max_ms: float | None = None
    period_std_ms: float | None = None
    bandwidth_bps: float | None = None
    mean_size_bytes: float | None = None
    stamped: bool = False
    delay_mean_ms: float | None = None
    delay_p95_ms: float | None = None
    age_ms: float | None = None
    usual_rate_hz: float | None = None
    malformed_stamps: int = 0
    qos_note: str | None = None
    note: str | None = None
    publisher_nodes: tuple[str, ...] = ()  # fully qualified node names, where the graph has them
    subscriber_nodes: tuple[str, ...] = ()
    rate_history: tuple[float | None, ...] = ()  # Hz once a second, oldest first (None: no rate then)
    steady: bool = False  # its rhythm is steady now: if it stops, it is ``silent`` (else ``quiet``)

    def to_json(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else _finite(v) for k, v in self.__dict__.items()}


def _finite(v: Any) -> Any:
    return None if isinstance(v, float) and not math.isfinite(v) else v


def unknown(f: TopicFigures, reason: str) -> TopicFigures:
    """``f`` while the monitor that measures it is down (``reason``: "monitor restarted: …"): its state
    ``unknown`` and the reason its note, its figures as they were; a topic the monitor cannot read at all
    stays ``unmeasured``."""
    if f.state == "unmeasured":
        return f
    return dataclasses.replace(f, state="unknown", note=reason)


class TopicWindow:
    """The messages of one topic received in the last ``window_s`` seconds (receive times monotonic)."""

    def __init__(
        self,
        name: str,
        type_name: str,
        window_s: float = WINDOW_S,
        stamped: bool = False,
        created: float | None = None,
    ) -> None:
        self.name = name
        self.type = type_name
        self.window_s = window_s
        self.stamped = stamped
        self.created = created  # when watching began (monotonic s); None: not known
        self.rhythm = Rhythm(window_s)
        self.times: deque[float] = deque(maxlen=MAX_SAMPLES)
        self.sizes: deque[int] = deque(maxlen=MAX_SAMPLES)
        self.delays: deque[tuple[float, float]] = deque(maxlen=MAX_SAMPLES)  # (receive time, delay s)
        self.total = 0
        self.last: float | None = None  # the latest message's receive time, in the window or not
        self.malformed_stamps = 0
        self.usual_hz: float | None = None
        self._usual_at = 0.0
        self.unmeasured: str | None = None  # why the backend cannot take this topic's messages
        self.rate_history: deque[float | None] = deque(maxlen=RATE_HISTORY)
        self._sampled: float | None = None  # when the newest rate sample is due from

    def add(self, now: float, size: int, delay_s: float | None = None) -> None:
        """One message, received at ``now`` (monotonic s), ``size`` bytes, ``delay_s`` behind its stamp."""
        if self.total == 0 and self.created is not None and now - self.created >= self.window_s:
            self.rhythm.on_demand = True  # on the graph a window or more before it had anything to say
        self.rhythm.add(now)
        self.times.append(now)
        self.sizes.append(size)
        self.total += 1
        self.last = now if self.last is None else max(self.last, now)
        if delay_s is not None:
            self.delays.append((now, delay_s))

    def bad_stamp(self) -> None:
        self.malformed_stamps += 1

    def _trim(self, now: float) -> None:
        start = now - self.window_s
        while self.times and self.times[0] < start:
            self.times.popleft()
            self.sizes.popleft()
        while self.delays and self.delays[0][0] < start:
            self.delays.popleft()

    def _rate(self) -> float | None:
        """(n - 1) / (t_last - t_first) over the window (after ``_trim``); None under two messages."""
        n = len(self.times)
        span = self.times[-1] - self.times[0] if n >= 2 else 0.0
        return (n - 1) / span if span > 0 else None

    def sample(self, now: float) -> None:
        """The rate history's samples due by ``now``: one per SAMPLE_S since the first (a call that
        comes late fills the seconds it missed with the rate now). Call it as often as you like."""
        if self._sampled is None:
            due, self._sampled = 1, now
        else:
            due = int((now - self._sampled) // SAMPLE_S)
            if due <= 0:
                return
            self._sampled += due * SAMPLE_S
        self._trim(now)
        rate = self._rate()
        value = None if rate is None else float(f"{rate:.4g}")  # what a plot can show, in a short JSON
        self.rate_history.extend([value] * min(due, RATE_HISTORY))

    def figures(
        self,
        now: float,
        publishers: int = 0,
        subscribers: int = 0,
        qos_note: str | None = None,
        nodes: tuple[tuple[str, ...], tuple[str, ...]] = ((), ()),
    ) -> TopicFigures:
        self._trim(now)
        times, n = self.times, len(self.times)
        rate = period_min = period_max = period_std = bw = mean_size = None
        if n >= 2:
            span = times[-1] - times[0]
            if span > 0:
                rate = self._rate()
                periods = [b - a for a, b in zip(times, list(times)[1:], strict=False)]
                mean_p = span / (n - 1)
                period_min, period_max = min(periods) * 1e3, max(periods) * 1e3
                period_std = math.sqrt(sum((p - mean_p) ** 2 for p in periods) / len(periods)) * 1e3
                bw = sum(self.sizes) / span * (n - 1) / n
        if n:
            mean_size = sum(self.sizes) / n
        delays = [d for _, d in self.delays]
        delay_mean = sum(delays) / len(delays) * 1e3 if delays else None
        delay_p95 = percentile(delays, 0.95) * 1e3 if delays else None
        age = None if self.last is None else (now - self.last) * 1e3  # None: never a message
        usual = self._usual(now, rate)
        if self.unmeasured is not None:
            state = "unmeasured"
        elif self.total == 0:
            state = "waiting"
        elif self.rhythm.stopped(now):
            state = "silent"
        elif n == 0:
            state = "quiet"
        elif rate is not None and usual is not None and rate < SLOW_FRACTION * usual:
            state = "slow"
        else:
            state = "ok"
        return TopicFigures(
            name=self.name,
            type=self.type,
            state=state,
            publishers=publishers,
            subscribers=subscribers,
            count=n,
            total=self.total,
            rate_hz=rate,
            period_min_ms=period_min,
            period_max_ms=period_max,
            period_std_ms=period_std,
            bandwidth_bps=bw,
            mean_size_bytes=mean_size,
            stamped=self.stamped,
            delay_mean_ms=delay_mean,
            delay_p95_ms=delay_p95,
            age_ms=age,
            usual_rate_hz=usual,
            malformed_stamps=self.malformed_stamps,
            qos_note=qos_note,
            note=self.unmeasured,
            publisher_nodes=nodes[0],
            subscriber_nodes=nodes[1],
            rate_history=tuple(self.rate_history),
            steady=self.rhythm.steady(),
        )

    def _usual(self, now: float, rate: float | None) -> float | None:
        """The highest rate seen, decaying towards lower ones with a half-life of USUAL_HALF_LIFE_S.
        Only a window that is full (the topic has been watched for a whole window) counts."""
        if self.usual_hz is not None:
            self.usual_hz *= 0.5 ** ((now - self._usual_at) / USUAL_HALF_LIFE_S)
        self._usual_at = now
        full = bool(self.times) and self.total > len(self.times)  # older messages fell out: a whole window
        if rate is not None and full and (self.usual_hz is None or rate > self.usual_hz):
            self.usual_hz = rate
        return self.usual_hz


class Rhythm:
    """One topic's rhythm, message by message (O(1) each): its period and the period's spread as
    exponentially weighted averages over about ``tau_s`` of time (each period weighs by its length), the
    current stretch without a pause, and whether the topic has shown it publishes on demand."""

    def __init__(self, tau_s: float) -> None:
        self.tau_s = tau_s
        self.last: float | None = None  # the latest message's receive time
        self.since: float | None = None  # when the current stretch (no pause) began
        self.gaps = 0  # periods in the current stretch
        self.period = 0.0  # s, their weighted mean
        self.var = 0.0  # s², their weighted variance
        self.on_demand = False  # it waited for its first message, or paused and came back

    def pause_after(self) -> float:
        """The gap that breaks the rhythm: STOP_PERIODS of its periods, at least STOP_MIN_S; while the
        period is not known, a whole window."""
        if self.gaps < MIN_GAPS:
            return self.tau_s
        return max(STOP_PERIODS * self.period, STOP_MIN_S)

    def add(self, now: float) -> None:
        if self.last is None:
            self.since = now
        else:
            gap = max(0.0, now - self.last)
            if gap >= self.pause_after():  # a pause: it came back, so it publishes on demand
                self.on_demand = True
                self.since, self.gaps, self.period, self.var = now, 0, 0.0, 0.0
            elif self.gaps == 0:
                self.gaps, self.period = 1, gap
            else:
                alpha = min(1.0, gap / self.tau_s)
                diff = gap - self.period
                self.period += alpha * diff
                self.var = (1.0 - alpha) * (self.var + alpha * diff * diff)
                self.gaps += 1
        self.last = now

    def regular(self) -> bool:
        return self.gaps >= MIN_GAPS and math.sqrt(self.var) <= REGULAR_CV * self.period

    def steady(self) -> bool:
        """Regular, without a pause, for a whole window, and either from the start or for STEADY_S."""
        if self.last is None or self.since is None or not self.regular():
            return False
        stretch = self.last - self.since
        return stretch >= self.tau_s and (stretch >= STEADY_S or not self.on_demand)

    def stopped(self, now: float) -> bool:
        """Steady up to its latest message, and nothing since for STOP_PERIODS of its periods."""
        return self.last is not None and self.steady() and now - self.last >= self.pause_after()


# -- QoS compatibility, from the graph's endpoint profiles -------------------------------------------
def qos_mismatch(publishers: list[tuple[str, str]], subscribers: list[tuple[str, str]]) -> str | None:
    """A note when some subscriber cannot match some publisher, from (reliability, durability) pairs
    (lower-case names: ``reliable``/``best_effort``, ``transient_local``/``volatile``): a reliable reader
    matches no best-effort writer; a transient-local reader no volatile writer."""
    notes = []
    if any(r == "reliable" for r, _ in subscribers) and any(r == "best_effort" for r, _ in publishers):
        notes.append("a reliable subscriber cannot match a best-effort publisher")
    if any(d == "transient_local" for _, d in subscribers) and any(d == "volatile" for _, d in publishers):
        notes.append("a transient-local subscriber cannot match a volatile publisher")
    return "; ".join(notes) or None


# -- the console's side: parse an answer ----------------------------------------------------------
_NUMBER_FIELDS = (
    "rate_hz", "period_min_ms", "period_max_ms", "period_std_ms", "bandwidth_bps", "mean_size_bytes",
    "delay_mean_ms", "delay_p95_ms", "age_ms", "usual_rate_hz",
)  # fmt: skip
_COUNT_FIELDS = ("publishers", "subscribers", "count", "total", "malformed_stamps")


def _topic(obj: Any) -> TopicFigures:
    if not isinstance(obj, dict):
        raise TopicsError("a topic is not an object")
    name, type_name, state = obj.get("name"), obj.get("type"), obj.get("state")
    if not isinstance(name, str) or not isinstance(type_name, str):
        raise TopicsError("a topic has no name or type")
    if state not in STATES:
        raise TopicsError(f"{name}: unknown state {state!r}")
    values: dict[str, Any] = {}
    for key in _NUMBER_FIELDS:
        v = obj.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v)):
            raise TopicsError(f"{name}: {key} is not a number")
        values[key] = None if v is None else float(v)
    for key in _COUNT_FIELDS:
        v = obj.get(key, 0)
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise TopicsError(f"{name}: {key} is not a count")
        values[key] = v
    notes: dict[str, Any] = {k: v if isinstance(v := obj.get(k), str) else None for k in ("qos_note", "note")}
    nodes: dict[str, Any] = {k: _names(obj.get(k), name, k) for k in ("publisher_nodes", "subscriber_nodes")}
    stamped = obj.get("stamped") is True
    steady = obj.get("steady") is True  # an older backend does not say: not known to be steady
    history = _history(obj.get("rate_history"), name)
    return TopicFigures(
        name=name, type=type_name, state=state, stamped=stamped, steady=steady, rate_history=history,
        **values, **notes, **nodes,
    )  # fmt: skip


def _history(v: Any, topic: str) -> tuple[float | None, ...]:
    """A rate history (absent from a backend that predates it: empty), its last RATE_HISTORY samples."""
    if v is None:
        return ()
    ok = isinstance(v, list) and all(
        x is None or (isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) and x >= 0)
        for x in v
    )
    if not ok:
        raise TopicsError(f"{topic}: rate_history is not a list of rates")
    return tuple(None if x is None else float(x) for x in v[-RATE_HISTORY:])


def _names(v: Any, topic: str, key: str) -> tuple[str, ...]:
    if v is None:
        return ()
    if not isinstance(v, list) or not all(isinstance(n, str) for n in v):
        raise TopicsError(f"{topic}: {key} is not a list of names")
    return tuple(v)


@dataclass(frozen=True)
class TopicsAnswer:
    window_s: float
    topics: tuple[TopicFigures, ...]
    skipped: int = 0  # topics in the answer that were not the documented shape
    interrupted: str | None = None  # why the states are ``unknown``: the monitor is restarting or failed


def parse_topics(body: Any) -> TopicsAnswer:
    """``GET /api/topics`` -> typed figures; a malformed topic is skipped and counted, a malformed answer
    raises :class:`TopicsError`."""
    if not isinstance(body, dict) or not isinstance(body.get("topics"), list):
        raise TopicsError("not a topics answer (no 'topics' list)")
    window = body.get("window_s")
    if isinstance(window, bool) or not isinstance(window, int | float) or not window > 0:
        raise TopicsError("window_s is not a positive number")
    topics, skipped = [], 0
    for obj in body["topics"]:
        try:
            topics.append(_topic(obj))
        except TopicsError:
            skipped += 1
    why = body.get("interrupted")
    interrupted = why[:200] if isinstance(why, str) and why else None
    return TopicsAnswer(float(window), tuple(sorted(topics, key=lambda t: t.name)), skipped, interrupted)


# -- expectations: "is every expected topic above its rate?" ---------------------------------------
@dataclass(frozen=True)
class Expectation:
    topic: str
    min_hz: float


def parse_expect(text: str) -> list[Expectation]:
    """``'/scan>=9.5,/odom>=45'`` -> expectations; a bad item raises ValueError naming it."""
    out = []
    for item in (part.strip() for part in text.split(",")):
        if not item:
            continue
        topic, sep, value = item.partition(">=")
        try:
            hz = float(value)
        except ValueError:
            hz = math.nan
        if not sep or not topic.strip().startswith("/") or not math.isfinite(hz) or hz < 0:
            raise ValueError(f"bad expectation {item!r}: write TOPIC>=HZ, e.g. /scan>=9.5")
        out.append(Expectation(topic.strip(), hz))
    if not out:
        raise ValueError("no expectation given: write TOPIC>=HZ[,TOPIC>=HZ...]")
    return out


def unmet(expectations: list[Expectation], answer: TopicsAnswer) -> list[str]:
    """One reason per expectation not met, in the order given; empty when all are."""
    by_name = {t.name: t for t in answer.topics}
    reasons = []
    for e in expectations:
        t = by_name.get(e.topic)
        if t is None:
            reasons.append(f"{e.topic}: not on the graph (expected >= {e.min_hz:g} Hz)")
        elif t.state == "unknown":  # the monitor is restarting: its rate cannot be vouched for
            reasons.append(f"{e.topic}: not known now ({t.note}), expected >= {e.min_hz:g} Hz")
        elif t.rate_hz is None or t.rate_hz < e.min_hz:
            have = "no messages" if t.rate_hz is None else f"{t.rate_hz:.2f} Hz"
            reasons.append(
                f"{e.topic}: {have} in the last {answer.window_s:g} s, expected >= {e.min_hz:g} Hz"
            )
    return reasons
