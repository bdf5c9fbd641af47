"""Services and actions that a WebSocket client provides (``advertise_service``, ``advertise_action``).

Transport-free: the endpoint keeps one provider per name, and whoever calls it (another WebSocket
client on either transport, or a ROS node through the rclpy service or action server that
``ros/interfaces.py`` puts on the graph for it) goes through the same three steps:

- a call becomes a ``call_service`` frame to the provider, with an id of its own
  (``service_request:<service>:<n>``, numbered per advertisement, as rosbridge_server numbers them),
  and completes when the provider's ``service_response`` with that id arrives, or fails after
  ``timeout`` seconds, or when the provider unadvertises, is replaced, or disconnects;
- a goal becomes a ``send_action_goal`` frame (``action_goal:<action>:<n>``, ``feedback: true``); the
  provider's ``action_feedback`` frames reach the goal's feedback callback, its ``action_result`` ends
  it (``result: false`` aborts it); a cancel becomes a ``cancel_action_goal`` frame, and a provider
  that does not end a cancelled goal within ``CANCEL_GRACE_S`` has it ended as cancelled for it;
- a second advertisement of a name replaces the first provider (rosbridge_server does the same, with a
  warning); what was pending on the first fails with the reason.

Nothing here waits without a bound except a goal that runs (goals may run long, as actions do); a
goal ends when its provider ends it, is cancelled, or goes away.
"""

from __future__ import annotations

import asyncio
import itertools
import json
import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

log = logging.getLogger(__name__)

PROVIDER_TIMEOUT_S = 10.0  # a call to a provided service without a "timeout" (and every ROS-side call)
CANCEL_GRACE_S = 5.0  # a cancelled goal its provider does not end within this is ended as cancelled

# action_msgs/msg/GoalStatus
STATUS_UNKNOWN = 0
STATUS_EXECUTING = 2
STATUS_SUCCEEDED = 4
STATUS_CANCELED = 5
STATUS_ABORTED = 6
FINAL_STATUSES = (STATUS_SUCCEEDED, STATUS_CANCELED, STATUS_ABORTED)


class Sender(Protocol):
    """A provider: a WebSocket client, as the endpoint has it."""

    id: int

    def send(self, frame: str) -> None: ...


class CallFailed(Exception):
    """A call or goal that ended without the provider's answer; the text says why."""


def _dumps(obj: Any) -> str:
    return json.dumps(obj, separators=(",", ":"), allow_nan=False)


@dataclass
class ProvidedService:
    name: str  # resolved: /arm/home
    type_name: str
    provider: Sender
    given: str = ""  # the name as the provider wrote it (arm/home): its frames carry it back, as rosbridge's
    withdraw: Callable[[], None] | None = None  # takes the ROS service off the graph (ROS mode)
    pending: dict[str, asyncio.Future[tuple[bool, Any]]] = field(default_factory=dict)
    _ids: itertools.count[int] = field(default_factory=lambda: itertools.count(1))

    async def call(self, args: Any, timeout: float = PROVIDER_TIMEOUT_S) -> tuple[bool, Any]:
        """(result, values) as the provider answered (``result: false`` passed through); CallFailed
        when it did not answer within ``timeout`` or went away meanwhile."""
        req_id = f"service_request:{self.given or self.name}:{next(self._ids)}"
        done: asyncio.Future[tuple[bool, Any]] = asyncio.get_running_loop().create_future()
        self.pending[req_id] = done
        frame = {"op": "call_service", "id": req_id, "service": self.given or self.name, "args": args}
        self.provider.send(_dumps(frame))
        try:
            return await asyncio.wait_for(asyncio.shield(done), timeout)
        except (TimeoutError, asyncio.TimeoutError):
            raise CallFailed(f"{self.name}: no response from its provider within {timeout:g} s") from None
        finally:
            self.pending.pop(req_id, None)

    def answer(self, req_id: Any, result: bool, values: Any) -> bool:
        """The provider's ``service_response``; False when no call with ``req_id`` is pending."""
        done = self.pending.get(req_id) if isinstance(req_id, str) else None
        if done is None or done.done():
            return False
        done.set_result((result, values))
        return True

    def fail_all(self, reason: str) -> None:
        for done in self.pending.values():
            if not done.done():
                done.set_exception(CallFailed(reason))
        self.pending.clear()


@dataclass
class Goal:
    """One goal a provider runs for a caller."""

    id: str
    # (GoalStatus, values, ok): ok is false when the goal ended without a result from its provider
    # (``result: false``, provider gone, cancel unanswered): values is then the provider's or a reason
    result: asyncio.Future[tuple[int, Any, bool]]
    on_feedback: Callable[[Any], None] | None
    cancel_timer: asyncio.TimerHandle | None = None


@dataclass
class ProvidedAction:
    name: str
    type_name: str
    provider: Sender
    type_given: str = ""  # the type as the provider wrote it: goals carry it back so (as rosbridge's do)
    given: str = ""  # the name as the provider wrote it: its frames carry it back, as rosbridge's
    withdraw: Callable[[], None] | None = None
    goals: dict[str, Goal] = field(default_factory=dict)
    _ids: itertools.count[int] = field(default_factory=lambda: itertools.count(1))

    def start(self, args: Any, on_feedback: Callable[[Any], None] | None) -> Goal:
        """Send the goal to the provider; the returned goal's ``result`` completes when it ends."""
        goal = Goal(
            f"action_goal:{self.given or self.name}:{next(self._ids)}",
            asyncio.get_running_loop().create_future(),
            on_feedback,
        )
        self.goals[goal.id] = goal
        goal.result.add_done_callback(lambda _f: self._forget(goal))
        frame = {
            "op": "send_action_goal",
            "id": goal.id,
            "action": self.given or self.name,
            "action_type": self.type_given or self.type_name,
            "args": args,
            "feedback": True,
        }
        self.provider.send(_dumps(frame))
        return goal

    def _forget(self, goal: Goal) -> None:
        if goal.cancel_timer is not None:
            goal.cancel_timer.cancel()
        if self.goals.get(goal.id) is goal:
            del self.goals[goal.id]

    def cancel(self, goal: Goal) -> None:
        """Ask the provider to cancel; ended as cancelled for it if it does not within the grace time."""
        if goal.result.done() or goal.cancel_timer is not None:
            return
        self.provider.send(
            _dumps({"op": "cancel_action_goal", "id": goal.id, "action": self.given or self.name})
        )
        goal.cancel_timer = asyncio.get_running_loop().call_later(
            CANCEL_GRACE_S,
            self._end,
            goal,
            STATUS_CANCELED,
            f"{self.name}: cancelled; its provider did not end the goal within {CANCEL_GRACE_S:g} s",
            False,
        )

    @staticmethod
    def _end(goal: Goal, status: int, values: Any, ok: bool) -> None:
        if not goal.result.done():
            goal.result.set_result((status, values, ok))

    def feedback(self, goal_id: Any, values: Any) -> bool:
        goal = self.goals.get(goal_id) if isinstance(goal_id, str) else None
        if goal is None:
            return False
        if goal.on_feedback is not None:
            goal.on_feedback(values)
        return True

    def finish(self, goal_id: Any, status: int, values: Any, ok: bool = True) -> bool:
        """The provider's ``action_result``; False when no goal with ``goal_id`` is running."""
        goal = self.goals.get(goal_id) if isinstance(goal_id, str) else None
        if goal is None:
            return False
        self._end(goal, status, values, ok)
        return True

    def fail_all(self, reason: str) -> None:
        for goal in list(self.goals.values()):
            self._end(goal, STATUS_ABORTED, reason, False)
        self.goals.clear()
