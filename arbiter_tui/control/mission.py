"""The console's missions as one immutable value: what is selected, the run in progress (or the last
one), what ``g`` resumes, and why a mission was forgotten. Each run is an ``arbiter_core.mission.Mission``
(the value the robot-side controller uses too); every change here is a pure function from one state to
the next, and the control loop does the side effects (runs begun and ended in the store, the teleop
stop) beside each step. No I/O, no Textual."""

from __future__ import annotations

from dataclasses import dataclass, replace

from arbiter_core.controllers import MANUAL
from arbiter_core.kinematics import Pose
from arbiter_core.mission import Mission, Phase


@dataclass(frozen=True)
class MissionState:
    algorithm: str = MANUAL  # the controller selected (manual: the keys drive)
    selected: str = "square"  # the named mission ``n`` selects and ``g`` starts
    current: Mission | None = None  # the run in progress, or the last one
    interrupted: Mission | None = None  # a run stopped before its end: what ``g`` resumes
    acknowledged: bool = False  # a key was pressed since the last run ended: its line goes
    forgotten: str | None = None  # why a mission ``g`` would have resumed was forgotten (said once)

    @property
    def running(self) -> bool:
        return self.current is not None and self.current.running

    @property
    def finished(self) -> str | None:
        """``done: 4/4 in 20.7 s`` after a completed run, until the next run or key."""
        c = self.current
        if c is None or c.phase is not Phase.COMPLETED or self.acknowledged:
            return None
        return c.summary()

    def preview(self, pose: Pose | None = None) -> Mission:
        """The selected mission as ``g`` would start it from ``pose`` (None: from the origin)."""
        return Mission.named(self.selected, self.algorithm, pose)


def selecting_algorithm(state: MissionState, name: str) -> MissionState:
    """``name`` selected (the caller stopped any run first)."""
    return replace(state, algorithm=name)


def selecting_mission(state: MissionState, name: str) -> MissionState:
    """Named mission ``name`` selected; nothing left to resume, and the last run's line goes."""
    return replace(state, selected=name, interrupted=None, forgotten=None, acknowledged=True)


def starting(state: MissionState, mission: Mission) -> MissionState:
    """A run of ``mission`` begins."""
    return replace(state, current=mission, interrupted=None, acknowledged=False, forgotten=None)


def advancing(state: MissionState, pose: Pose) -> MissionState:
    """The run in progress passes the waypoints ``pose`` is within tolerance of; so does the mission ``g``
    resumes, while the robot is driven by hand (a waypoint passed on the way counts as reached)."""
    c, i = state.current, state.interrupted
    if c is not None and c.running:
        moved = c.advanced(pose)
        return state if moved is c else replace(state, current=moved)
    if i is not None:
        moved = i.advanced(pose)
        if moved is not i:
            return replace(state, interrupted=moved if moved.resumable else None)
    return state


def stopping(state: MissionState, phase: Phase, now_ms: float) -> MissionState:
    """The run (if any) ends now before its end (``phase``: aborted or overridden); what is left of it
    is what ``g`` resumes."""
    c = state.current
    if c is None or not c.running:
        return state
    ended = c.ended(phase, now_ms)
    return replace(state, current=ended, interrupted=ended if ended.resumable else state.interrupted)


def completing(state: MissionState, now_ms: float) -> MissionState:
    """The run reached its last waypoint now."""
    c = state.current
    if c is None or not c.running:
        return state
    return replace(state, current=c.ended(Phase.COMPLETED, now_ms), acknowledged=False)


def acknowledged(state: MissionState) -> MissionState:
    """A key was pressed: the last run's "done" line goes."""
    return state if state.acknowledged else replace(state, acknowledged=True)


def forgetting_interrupted(state: MissionState, why: str | None = None) -> MissionState:
    """Nothing to resume any more; ``why`` (a lost link, the odometry reset) is said when ``g`` next
    starts a mission afresh."""
    if state.interrupted is None:
        return state
    return replace(state, interrupted=None, forgotten=why)
