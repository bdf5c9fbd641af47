"""A mission's lifecycle as one immutable value: what is selected, what drives, what runs, what ``g``
resumes, what the last run did. Every change is a pure function from one state to the next; the
control loop holds the current state and does the side effects (runs begun and ended in the store, the
teleop stop) beside each step. No I/O, no Textual."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from arbiter_core.controllers import MissionProgress

from ..analytics.runs import MANUAL

RESUMED = ", resumed"  # what a resumed run's label ends with (the panel shows which waypoint it is at)


@dataclass(frozen=True)
class Resumable:
    """A mission stopped before its end: ``g`` resumes it, with the controller and label it ran with."""

    progress: MissionProgress
    algorithm: str
    label: str

    @property
    def goal(self) -> tuple[float, float]:
        return self.progress.goal

    @property
    def done(self) -> bool:
        return self.progress.done


@dataclass(frozen=True)
class MissionState:
    algorithm: str = MANUAL  # the controller selected (manual: the keys drive)
    selected: str = "square"  # the named mission ``n`` selects and ``g`` starts
    progress: MissionProgress = field(default_factory=lambda: MissionProgress.named("square"))
    label: str = "square"  # what the current (or last) run drives: a mission's name or a goal
    running: bool = False  # an autonomous controller is driving
    interrupted: Resumable | None = None
    finished: str | None = None  # "done: 4/4 in 20.7 s" until the next run or key
    started_ms: float = 0.0  # wall ms the current (or last) run began


def selecting_algorithm(state: MissionState, name: str) -> MissionState:
    """``name`` selected (the caller stopped any run first)."""
    return replace(state, algorithm=name)


def selecting_mission(state: MissionState, name: str) -> MissionState:
    """Named mission ``name`` selected, from its first waypoint; nothing left to resume."""
    return replace(state, selected=name, label=name, progress=MissionProgress.named(name), interrupted=None)


def starting(state: MissionState, progress: MissionProgress, label: str, now_ms: float) -> MissionState:
    """A run of ``progress`` begins now."""
    return replace(
        state,
        progress=progress,
        label=label,
        interrupted=None,
        running=True,
        finished=None,
        started_ms=now_ms,
    )


def stopping(state: MissionState) -> MissionState:
    """The run (if any) ends before its end: what is left of it is what ``g`` resumes."""
    if not state.running:
        return state
    interrupted = state.interrupted
    if not state.progress.done:
        interrupted = Resumable(state.progress, state.algorithm, state.label.removesuffix(RESUMED))
    return replace(state, running=False, interrupted=interrupted)


def completing(state: MissionState, now_ms: float) -> MissionState:
    """The run reached its last waypoint now."""
    n = len(state.progress.waypoints)
    done = f"done: {n}/{n} in {(now_ms - state.started_ms) / 1000.0:.1f} s"
    return replace(state, running=False, finished=done)


def acknowledged(state: MissionState) -> MissionState:
    """A key was pressed: the last run's "done" line goes."""
    return state if state.finished is None else replace(state, finished=None)


def forgetting_interrupted(state: MissionState) -> MissionState:
    return state if state.interrupted is None else replace(state, interrupted=None)
