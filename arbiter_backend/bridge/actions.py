"""Action ops: goals clients send (``send_action_goal``, ``cancel_action_goal``) and actions clients
provide (``advertise_action``, ``action_feedback``, ``action_result``, ``unadvertise_action``).

A goal reaches, in this order, an action another client provides (a ``send_action_goal`` frame to
it, ``action_goal:<action>:<n>``; its ``action_feedback`` and ``action_result`` come back to the
caller) or, in ROS mode, any action server on the graph (``ros/interfaces.py``). A goal runs beside
the client's other frames until its server or provider ends it, it is cancelled, or either side goes
away; a client that disconnects has its goals cancelled. In ROS mode a provided action is also an
rclpy action server on the graph, and values are checked against the type's Goal, Feedback and
Result. ``--actions-glob`` bounds both ways.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import Any

from arbiter_core.msgtypes import MessageError

from ..provided import FINAL_STATUSES, STATUS_ABORTED, STATUS_UNKNOWN, ProvidedAction
from . import frames
from .client import Client
from .exposure import Exposure
from .frames import BadFrame, Frame, dumps
from .providers import Providers

log = logging.getLogger(__name__)


class ActionRoom:
    def __init__(self, interfaces: Any, exposure: Exposure) -> None:
        self.interfaces = interfaces  # ROS mode: ros.interfaces.RosInterfaces; None on the embedded bus
        self.exposure = exposure
        self.provided: Providers[ProvidedAction] = Providers("action", exposure.name)

    # -- goals clients send ----------------------------------------------------------------------------
    def send_action_goal(self, client: Client, frame: Frame) -> None:
        client.room_for_call()
        action = self.exposure.action(frame)
        req_id = frame.get("id")
        if req_id is not None and not isinstance(req_id, (str, int)):
            raise BadFrame("field 'id' must be a string or an integer")
        feedback = frames.field(frame, "feedback", bool, required=False) is True
        if req_id is not None and req_id in client.goals:
            raise BadFrame(f"a goal with id {req_id!r} is running already: give each goal its own id")
        args = frame.get("args", {})
        provided = self.provided.get(action)
        type_name = frames.interface_type(frame, "action_type", "action", self.interfaces)
        if provided is None and self.interfaces is None:
            self._goal_ended(client, action, req_id, STATUS_UNKNOWN, f"Action {action} does not exist", False)
            return
        if self.interfaces is not None:
            args = self.interfaces.values(type_name, "Goal", args, path="args")  # MessageError: status
        ended: list[bool] = []  # the result went out: later feedback is not sent (ROS carries feedback
        # and result on different channels, so the last feedback can arrive after the result)

        def feedback_until_ended(values: Any) -> None:
            if not ended:
                self._goal_feedback(client, action, req_id, values)

        on_feedback = feedback_until_ended if feedback else None
        if provided is not None:
            goal = provided.start(args, on_feedback)
            if req_id is not None:
                client.goals[req_id] = lambda: provided.cancel(goal)
            client.track(self._await_provided_goal(client, action, req_id, goal.result, ended))
            return
        ros_goal = self.interfaces.new_goal()
        if req_id is not None:
            client.goals[req_id] = ros_goal.cancel
        client.track(
            self._await_ros_goal(client, action, type_name, req_id, args, on_feedback, ros_goal, ended),
        )

    def _goal_feedback(self, client: Client, action: str, req_id: Any, values: Any) -> None:
        frame: dict[str, Any] = {"op": "action_feedback", "action": action, "values": values}
        if req_id is not None:
            frame["id"] = req_id
        client.send(dumps(frame))

    def _goal_ended(
        self, client: Client, action: str, req_id: Any, status: int, values: Any, result: bool
    ) -> None:
        if req_id is not None:
            client.goals.pop(req_id, None)
        frame: dict[str, Any] = {"op": "action_result", "action": action, "values": values}
        frame.update(status=status, result=result)
        if req_id is not None:
            frame["id"] = req_id
        client.send(dumps(frame))

    async def _await_provided_goal(
        self,
        client: Client,
        action: str,
        req_id: Any,
        result: asyncio.Future[tuple[int, Any, bool]],
        ended: list[bool],
    ) -> None:
        status, values, ok = await result
        ended.append(True)
        self._goal_ended(client, action, req_id, status, values, ok)

    async def _await_ros_goal(
        self,
        client: Client,
        action: str,
        type_name: str,
        req_id: Any,
        args: Any,
        on_feedback: Callable[[Any], None] | None,
        goal: Any,
        ended: list[bool],
    ) -> None:
        try:
            try:
                status, values = await self.interfaces.send_goal(action, type_name, args, on_feedback, goal)
            finally:
                ended.append(True)
        except MessageError as exc:
            self._goal_ended(client, action, req_id, STATUS_UNKNOWN, str(exc), False)
        except Exception as exc:
            log.exception("goal to %s failed", action)
            self._goal_ended(client, action, req_id, STATUS_UNKNOWN, f"{action}: {type(exc).__name__}", False)
        else:
            self._goal_ended(client, action, req_id, status, values, True)

    def cancel_action_goal(self, client: Client, frame: Frame) -> None:
        self.exposure.name(frame, "action")
        if "id" not in frame:
            raise BadFrame("missing field 'id' (the id of the goal to cancel)")
        req_id = frame["id"]
        cancel = client.goals.get(req_id) if isinstance(req_id, (str, int)) else None
        if cancel is None:
            raise BadFrame(f"no goal with id {str(req_id)[:80]!r} is running for this client")
        cancel()

    def cancel_goals(self, client: Client) -> None:
        """``client`` is gone: a goal does not go on without it."""
        for cancel_goal in list(client.goals.values()):
            cancel_goal()
        client.goals.clear()

    # -- actions clients provide -----------------------------------------------------------------------
    def advertise_action(self, client: Client, frame: Frame) -> None:
        name = self.exposure.action(frame)
        type_name = frames.interface_type(frame, "type", "action", self.interfaces)
        act = ProvidedAction(name, type_name, client, type_given=frame["type"], given=frame["action"])
        if self.interfaces is not None:
            act.withdraw = self.interfaces.advertise_action(name, type_name, act.start, act.cancel)
        self.provided.install(client, frame, act)

    def action_feedback(self, client: Client, frame: Frame) -> None:
        act = self.provided.owned(client, frame)
        goal_id = frames.field(frame, "id", str)
        values = frames.field(frame, "values", dict)
        if self.interfaces is not None:
            values = self.interfaces.values(act.type_name, "Feedback", values)
        if not act.feedback(goal_id, values):
            raise BadFrame(f"no goal of {act.name} with id {goal_id[:80]!r} is running")

    def action_result(self, client: Client, frame: Frame) -> None:
        act = self.provided.owned(client, frame)
        goal_id = frames.field(frame, "id", str)
        result = frames.field(frame, "result", bool)
        status = frames.field(frame, "status", int, required=result)
        values = frame.get("values", {})
        if result:
            if status not in FINAL_STATUSES:
                raise BadFrame(f"status must be a final GoalStatus (4, 5 or 6), got {status}")
            if not isinstance(values, dict):
                raise BadFrame("values must be an object when result is true")
            if self.interfaces is not None:
                try:
                    values = self.interfaces.values(act.type_name, "Result", values)
                except MessageError as exc:  # the goal ends now, aborted, not never
                    why = f"{act.name}: its provider's result does not fit"
                    act.finish(goal_id, STATUS_ABORTED, why, False)
                    raise BadFrame(f"values: {exc}") from None
        elif status is None:
            status = STATUS_ABORTED
        elif status not in FINAL_STATUSES:
            raise BadFrame(f"status must be a final GoalStatus (4, 5 or 6), got {status}")
        if not act.finish(goal_id, status, values, result):
            raise BadFrame(f"no goal of {act.name} with id {goal_id[:80]!r} is running")
