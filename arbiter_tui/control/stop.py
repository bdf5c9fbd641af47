"""What "stop" means, in each mode, in one place (docs/drive.md, "Safety"), and what a stop did, in words.

Every stop key, on every screen, dialog and text input, ends in ``RobotSession.stop_all``: the console's
own driving stops at once (a held key, a mission: one zero command now, on its own stamped path), and
in a mode where something else may drive, the rest of :class:`StopScope` is asked on a thread of its own
(``session/remote_stop.py``), which reports back a :class:`StopReport`:

- **the robot-side controller** (``arbiter-backend --autonomy``, the tracker's ``DELETE /api/autonomy``):
  in every mode with a backend (embedded, connect, observe);
- **a foreign controller behind a ROS action** (observe mode; Nav2's action names by default, or
  ``--stop-actions``): every goal is cancelled (``action_msgs/srv/CancelGoal`` with a zero goal id and
  stamp, on ``<action>/_action/cancel_goal``, through rosbridge's ``call_service``);
- **zero velocity on the observed command topic** (observe mode) for ``ZERO_FOR_S`` after the answers:
  a controller that is still publishing overrides it, and the report says so.

Pure: no I/O, no Textual.
"""

from __future__ import annotations

from dataclasses import dataclass

from arbiter_core import topics
from arbiter_core.stopping import (  # shared with the robot's answer to a fleet console's stop
    CANCEL_ALL,
    CANCEL_SUFFIX,
    CANCEL_TIMEOUT_S,
    CANCEL_TYPE,
    NAV2_ACTIONS,
    ZERO_FOR_S,
    ZERO_HZ,
    ActionCancel,
    Cancel,
    cancel_failure,
    cancel_outcome,
)


@dataclass(frozen=True, slots=True)
class StopScope:
    """What a stop reaches beyond the console's own commands."""

    robot_side: bool = False  # ask the backend's robot-side controller to stop
    actions: tuple[str, ...] = ()  # resolved action names whose goals are cancelled
    zero_topic: str | None = None  # resolved command topic given zero velocity for ZERO_FOR_S
    zero_stamped: bool = False  # ...as geometry_msgs/TwistStamped

    @property
    def remote(self) -> bool:
        return self.robot_side or bool(self.actions) or self.zero_topic is not None


def stop_scope(
    simulated: bool,
    observe: bool,
    namespace: str = "",
    cmd_topic: str = "cmd_vel",
    cmd_stamped: bool = False,
    actions: tuple[str, ...] | None = None,
) -> StopScope:
    """The one definition of what a stop reaches (module doc). ``actions``: the action names to cancel
    (None: Nav2's in observe mode, none otherwise); relative names resolve under ``namespace``."""
    if simulated:
        return StopScope()
    chosen = (NAV2_ACTIONS if observe else ()) if actions is None else actions
    resolved = tuple(dict.fromkeys(topics.resolve(a, namespace, what="action") for a in chosen))
    return StopScope(
        robot_side=True,
        actions=resolved,
        zero_topic=topics.resolve(cmd_topic, namespace) if observe else None,
        zero_stamped=cmd_stamped,
    )


@dataclass(frozen=True, slots=True)
class RobotSideStop:
    """What the robot-side controller said to the stop (``DELETE /api/autonomy``)."""

    stopped: bool = False  # a run was in progress and is aborted now
    run: str = ""  # "stanley on corner at 1/2"
    error: str | None = None  # could not ask (unreachable, refused); None: asked
    enabled: bool = True  # False: the backend runs without --autonomy (403): nothing of ours drives there


@dataclass(frozen=True, slots=True)
class StopReport:
    """What one stop did beyond the console's own zero, as the screen says it."""

    robot_side: RobotSideStop | None = None  # None: not asked
    cancels: tuple[ActionCancel, ...] = ()
    zero_topic: str | None = None
    zero_for_s: float = 0.0
    link_down: bool = False  # nothing could be sent or asked: the link to the robot is down

    @property
    def unsure(self) -> bool:
        """The stop may not have reached what drives: shown as a warning."""
        if self.link_down:
            return True
        rs = self.robot_side
        if rs is not None and rs.error is not None and rs.enabled:
            return True
        if any(c.outcome is Cancel.FAILED for c in self.cancels):
            return True
        return bool(self.cancels) and not any(c.outcome is Cancel.CANCELLED for c in self.cancels) and (
            not (self.robot_side and self.robot_side.stopped)
        )

    def worth_saying(self) -> bool:
        """Outside observe mode a stop that found nothing robot-side to stop needs no words."""
        return bool(self.cancels) or self.zero_topic is not None or self.link_down or (
            self.robot_side is not None
            and (self.robot_side.stopped or (self.robot_side.error is not None and self.robot_side.enabled))
        )

    def text(self) -> str:
        """One line: what was stopped, what could not be, and what that leaves."""
        parts: list[str] = []
        if self.link_down:
            parts.append("the link to the robot is down: no goal could be cancelled and no zero sent (the "
                         "robot stops on its deadman if commands stop)")  # fmt: skip
        rs = self.robot_side
        if rs is not None and rs.stopped:
            parts.append(f"stopped the robot-side {rs.run}")
        elif rs is not None and rs.error is not None and rs.enabled:
            parts.append(f"could not ask the robot-side controller: {rs.error}")
        cancelled = [c for c in self.cancels if c.outcome is Cancel.CANCELLED]
        for c in cancelled:
            parts.append(f"cancelled {c.goals} goal{'s' if c.goals != 1 else ''} of {c.action}")
        idle = [c.action for c in self.cancels if c.outcome is Cancel.NO_GOAL]
        if idle:
            parts.append(f"no goal running on {_names(idle)}")
        for c in self.cancels:
            if c.outcome is Cancel.FAILED:
                parts.append(f"could not cancel {c.action}: {c.detail}")
        missing = [c.action for c in self.cancels if c.outcome is Cancel.NO_SERVER]
        if missing and not cancelled and not idle:
            parts.append(f"no action server on {_names(missing)}")
        if self.zero_topic is not None:
            zero = f"zero velocity on {self.zero_topic} for {self.zero_for_s:g} s"
            if self.unsure:
                zero = f"sent {zero} only: a controller still publishing will override it"
            parts.append(zero)
        return "Stop: " + ("; ".join(parts) if parts else "nothing else was driving")


def _names(names: list[str], most: int = 2) -> str:
    shown = ", ".join(names[:most])
    return shown if len(names) <= most else f"{shown} and {len(names) - most} more"


__all__ = [
    "CANCEL_ALL", "CANCEL_SUFFIX", "CANCEL_TIMEOUT_S", "CANCEL_TYPE", "NAV2_ACTIONS", "ZERO_FOR_S", "ZERO_HZ",
    "ActionCancel", "Cancel", "RobotSideStop", "StopReport", "StopScope", "cancel_failure", "cancel_outcome",
    "stop_scope",
]  # fmt: skip
