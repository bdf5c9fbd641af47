"""Services and actions across the bridge in ROS mode: rclpy servers for what WebSocket clients
provide, an rclpy action client for the goals they send.

- ``advertise_service``: an rclpy service on the graph (node ``arbiter_bridge_provider``). Its callback
  hands the request to the endpoint's ``ProvidedService.call`` on the asyncio loop (a ``call_service``
  frame to the providing client) and waits, at most the call's timeout, for the client's
  ``service_response``. ROS 2 services have no error reply: when the provider answers
  ``result: false``, does not answer in time, or goes away, the ROS caller gets the type's default
  response (for std_srvs ``SetBool``/``Trigger``: ``success: false``) and the backend logs why.
- ``advertise_action``: an rclpy action server; each goal becomes a ``send_action_goal`` frame, the
  client's ``action_feedback`` is published as the goal's feedback, its ``action_result`` ends the goal
  (succeeded, canceled or aborted as its ``status`` says; ``result: false`` aborts); a ROS cancel
  request reaches the client as ``cancel_action_goal``.
- ``send_action_goal``: an rclpy ``ActionClient`` per action (kept, as the service clients are);
  feedback and the result come back to the asyncio loop; a client that disconnects has its goals
  cancelled on the graph.

The provided servers' callbacks block while they wait, so they run on their own node in a
``MultiThreadedExecutor`` (``PROVIDER_THREADS`` at once), never on the relay's single executor thread,
whose topic callbacks must not wait behind a WebSocket client. (An ``async`` rclpy callback would not
block, but rclpy's executor resumes pending coroutines on every turn: it would spin a core for as long
as a call waits.)
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import logging
import threading
from collections.abc import Callable, Coroutine
from typing import Any

from rclpy.action.client import ActionClient
from rclpy.action.server import ActionServer, CancelResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.context import Context
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node

from arbiter_core.msgtypes import MessageError

from ..provided import (
    FINAL_STATUSES,
    PROVIDER_TIMEOUT_S,
    STATUS_ABORTED,
    STATUS_CANCELED,
    STATUS_SUCCEEDED,
    Goal,
)
from ..supervise import Supervisor
from .convert import action_class, interface_name, service_class, to_json, to_ros
from .futures import on_loop
from .spin import spin_in_thread

log = logging.getLogger(__name__)

PROVIDER_NODE_NAME = "arbiter_bridge_provider"
PROVIDER_THREADS = 16  # provided calls and goals waiting at once before more queue
SERVER_WAIT_S = 1.0  # how long a goal waits for its action server to be matched (rosbridge: 1 s)
SERVER_GONE_S = 3.0  # an action server unseen this long while its goal runs has gone: the goal fails
RESULT_AGAIN_S = 1.0  # a goal the server reports ended whose result has not come: asked for again
GOAL_ANSWER_S = 5.0  # a goal request unanswered this long failed (its answer lost as the server matched us)


def _args(fields: dict[str, str], args: Any) -> dict[str, Any]:
    """rosbridge ``args``: an object keyed by field, a list in field order; anything else: defaults."""
    if isinstance(args, list):
        return dict(zip(fields, args, strict=False))
    return args if isinstance(args, dict) else {}


class RosGoal:
    """A goal a WebSocket client sent to an action server on the graph; cancellable at any time."""

    def __init__(self) -> None:
        self.handle: Any = None
        self.cancel_requested = False

    def cancel(self) -> None:
        self.cancel_requested = True
        if self.handle is not None:
            with contextlib.suppress(Exception):
                self.handle.cancel_goal_async()


class _Withdrawable:
    """A provided server taken off the graph only once no callback of it is under way: a service
    destroyed between its callback's return and the executor's sending of the response would leave
    the ROS caller without one. The destruction waits ``GRACE_S`` after the last callback returns."""

    GRACE_S = 0.2

    def __init__(self, loop: asyncio.AbstractEventLoop, destroy: Callable[[], object]) -> None:
        self.loop = loop
        self._destroy = destroy
        self._lock = threading.Lock()
        self.busy = 0
        self.withdrawn = False
        self.destroyed = False

    def enter(self) -> bool:
        with self._lock:
            if self.withdrawn:
                return False
            self.busy += 1
            return True

    def leave(self) -> None:
        with self._lock:
            self.busy -= 1
            last = self.withdrawn and self.busy == 0
        if last:
            with contextlib.suppress(RuntimeError):  # the loop is closed: shutting down
                self.loop.call_soon_threadsafe(self.loop.call_later, self.GRACE_S, self._destroy_once)

    def withdraw(self) -> None:  # asyncio loop
        with self._lock:
            self.withdrawn = True
            idle = self.busy == 0
        if idle:
            self._destroy_once()

    def _destroy_once(self) -> None:
        if not self.destroyed:
            self.destroyed = True
            try:
                self._destroy()
            except Exception:
                log.exception("taking a provided server off the graph failed")


class RosInterfaces:
    def __init__(
        self, node: Node, loop: asyncio.AbstractEventLoop, context: Context, supervisor: Supervisor
    ) -> None:
        self.node = node  # the relay's node: action clients
        self.loop = loop
        self.provider_node = Node(PROVIDER_NODE_NAME, context=context, start_parameter_services=False)
        self.executor = MultiThreadedExecutor(num_threads=PROVIDER_THREADS, context=context)
        self.executor.add_node(self.provider_node)
        self.group = ReentrantCallbackGroup()
        self._action_clients: dict[str, tuple[type, ActionClient[Any, Any, Any]]] = {}
        self._closed = False
        self._stop = threading.Event()
        self._thread = spin_in_thread(
            self.executor, self.provider_node, "rclpy-provider", supervisor, self._stop
        )

    # -- types and values -------------------------------------------------------------------
    @staticmethod
    def service_type(type_name: str) -> str:
        return interface_name(service_class(type_name), "srv")

    @staticmethod
    def action_type(type_name: str) -> str:
        return interface_name(action_class(type_name), "action")

    @staticmethod
    def values(type_name: str, part: str, values: Any, path: str = "values") -> dict[str, Any]:
        """``values`` checked against (and completed from) ``part`` (Request, Response, Goal, Feedback,
        Result) of the service or action ``type_name``; MessageError naming the field otherwise."""
        cls = (
            getattr(service_class(type_name), part)
            if "/srv/" in type_name
            else getattr(action_class(type_name), part)
        )
        if part in ("Request", "Goal"):
            values = _args(cls.get_fields_and_field_types(), values)
        return to_json(to_ros(cls, values, path=path))

    def _wait(self, future: concurrent.futures.Future[Any]) -> Any:
        """Block this worker thread until ``future`` (on the asyncio loop) is done or we shut down."""
        while True:
            try:
                return future.result(timeout=1.0)
            except concurrent.futures.TimeoutError:
                if self._closed:
                    future.cancel()
                    raise MessageError("the backend is shutting down") from None

    # -- services WebSocket clients provide ------------------------------------------------------
    def advertise_service(
        self, name: str, type_name: str, call: Callable[[Any, float], Coroutine[Any, Any, tuple[bool, Any]]]
    ) -> Callable[[], None]:
        """An rclpy service ``name`` whose requests go to ``call``; returns what takes it away."""
        srv = service_class(type_name)
        state = _Withdrawable(self.loop, lambda: self.provider_node.destroy_service(service))

        def callback(request: Any, response: Any) -> Any:  # a provider executor thread
            if not state.enter():
                return response  # withdrawn: the answer to a call that was on its way
            try:
                ok, values = self._wait(
                    asyncio.run_coroutine_threadsafe(call(to_json(request), PROVIDER_TIMEOUT_S), self.loop)
                )
            except Exception as exc:
                log.warning("%s: the ROS caller gets a default response: %s", name, exc)
                return response
            finally:
                state.leave()
            if not ok:
                log.warning("%s: its provider answered result false (%s); default response", name, values)
                return response
            try:
                return to_ros(srv.Response, values, path="values")
            except MessageError as exc:
                log.warning("%s: the provider's response does not fit: %s", name, exc)
                return response

        service = self.provider_node.create_service(srv, name, callback, callback_group=self.group)
        return state.withdraw

    # -- actions WebSocket clients provide -------------------------------------------------------
    def advertise_action(
        self,
        name: str,
        type_name: str,
        start: Callable[[Any, Callable[[Any], None] | None], Goal],
        cancel: Callable[[Goal], None],
    ) -> Callable[[], None]:
        """An rclpy action server ``name`` whose goals go to ``start``; returns what takes it away."""
        cls = action_class(type_name)
        running: dict[bytes, Goal] = {}  # asyncio loop only

        def execute(goal_handle: Any) -> Any:  # a provider executor thread
            if not state.enter():
                with contextlib.suppress(Exception):
                    goal_handle.abort()
                return cls.Result()
            try:
                return run_goal(goal_handle)
            finally:
                state.leave()

        def run_goal(goal_handle: Any) -> Any:
            key = bytes(goal_handle.goal_id.uuid)

            def feedback(values: Any) -> None:  # asyncio loop
                try:
                    goal_handle.publish_feedback(to_ros(cls.Feedback, values, path="values"))
                except Exception as exc:
                    log.warning("%s: feedback not published: %s", name, exc)

            async def run() -> tuple[int, Any, bool]:
                goal = start(to_json(goal_handle.request), feedback)
                running[key] = goal
                try:
                    return await goal.result
                finally:
                    running.pop(key, None)

            try:
                status, values, ok = self._wait(asyncio.run_coroutine_threadsafe(run(), self.loop))
            except Exception as exc:
                status, values, ok = STATUS_ABORTED, str(exc), False
            result = cls.Result()
            if ok and isinstance(values, dict):
                try:
                    result = to_ros(cls.Result, values, path="values")
                except MessageError as exc:
                    log.warning("%s: the provider's result does not fit: %s", name, exc)
                    status = STATUS_ABORTED
            try:
                if status == STATUS_SUCCEEDED:
                    goal_handle.succeed()
                elif status == STATUS_CANCELED and goal_handle.is_cancel_requested:
                    goal_handle.canceled()
                else:
                    goal_handle.abort()
            except Exception as exc:  # a transition the goal's state does not allow
                log.warning("%s: goal state: %s", name, exc)
            return result

        def on_cancel(goal_handle: Any) -> CancelResponse:  # an executor thread
            key = bytes(goal_handle.goal_id.uuid)

            def forward() -> None:
                goal = running.get(key)
                if goal is not None:
                    cancel(goal)

            with contextlib.suppress(RuntimeError):
                self.loop.call_soon_threadsafe(forward)
            return CancelResponse.ACCEPT

        state = _Withdrawable(self.loop, lambda: server.destroy())
        server = ActionServer(
            self.provider_node,
            cls,
            name,
            execute_callback=execute,
            cancel_callback=on_cancel,
            callback_group=self.group,
        )
        return state.withdraw

    # -- goals WebSocket clients send to the graph -----------------------------------------------
    @staticmethod
    def new_goal() -> RosGoal:
        return RosGoal()

    def _on_loop(self, future: Any) -> asyncio.Future[Any]:
        """An rclpy future as an asyncio one (its result crosses from the executor thread)."""
        return on_loop(self.loop, future)

    async def send_goal(
        self,
        action: str,
        type_name: str,
        args: Any,
        on_feedback: Callable[[Any], None] | None,
        goal: RosGoal,
    ) -> tuple[int, Any]:
        """Send a goal to the action server ``action``; (GoalStatus, result values) when it ends.
        MessageError when there is no server or the goal is rejected or does not fit the type."""
        cls = action_class(type_name)
        request = to_ros(cls.Goal, _args(cls.Goal.get_fields_and_field_types(), args), path="args")
        cached = self._action_clients.get(action)
        if cached is None or cached[0] is not cls:
            if cached is not None:
                with contextlib.suppress(Exception):
                    cached[1].destroy()
            cached = self._action_clients[action] = (cls, ActionClient(self.node, cls, action))
        client = cached[1]
        for _ in range(int(SERVER_WAIT_S / 0.05)):
            if client.server_is_ready():
                break
            await asyncio.sleep(0.05)
        else:
            raise MessageError(f"Action {action} is not available")

        try:
            sent = self._on_loop(
                client.send_goal_async(
                    request, feedback_callback=self._feedback_to_loop(on_feedback) if on_feedback else None
                )
            )
            try:
                # a goal request sent as the server first matches us can lose its answer (DDS discovery
                # is not symmetric): a failure the client can retry, never a wait without end
                handle = await asyncio.wait_for(sent, GOAL_ANSWER_S)
            except asyncio.TimeoutError:
                raise MessageError(
                    f"{action}: the action server did not answer the goal within {GOAL_ANSWER_S:g} s"
                ) from None
            if not handle.accepted:
                raise MessageError(f"{action}: the action server rejected the goal")
            goal.handle = handle
            if goal.cancel_requested:
                goal.cancel()
            response = await self._result(action, client, handle)
        except asyncio.CancelledError:
            goal.cancel()  # the client went away: its goal does not go on without it
            raise
        return response.status, to_json(response.result)

    def _feedback_to_loop(self, on_feedback: Callable[[Any], None]) -> Callable[[Any], None]:
        def feedback(message: Any) -> None:  # executor thread
            values = to_json(message.feedback)
            with contextlib.suppress(RuntimeError):
                self.loop.call_soon_threadsafe(on_feedback, values)

        return feedback

    async def _result(self, action: str, client: ActionClient[Any, Any, Any], handle: Any) -> Any:
        """The goal's result, never waited for without end: a result request whose answer is lost (one
        sent as the service first matches can be) is sent again once the status topic says the goal
        ended; a server that leaves the graph fails the goal."""
        waiting = {self._on_loop(handle.get_result_async())}
        gone_since = ended_since = None
        while True:
            done, _ = await asyncio.wait(waiting, timeout=0.5, return_when=asyncio.FIRST_COMPLETED)
            if done:
                return done.pop().result()
            now = self.loop.time()
            if client.server_is_ready():
                gone_since = None
            else:
                gone_since = gone_since or now
                if now - gone_since > SERVER_GONE_S:
                    raise MessageError(f"{action}: the action server left before the goal ended")
            if handle.status in FINAL_STATUSES:
                ended_since = ended_since or now
                if now - ended_since > RESULT_AGAIN_S:
                    log.info("%s: the goal ended but its result has not come; asking again", action)
                    waiting.add(self._on_loop(handle.get_result_async()))
                    ended_since = now

    def close(self) -> None:
        self._closed = True
        for _, client in self._action_clients.values():
            with contextlib.suppress(Exception):
                client.destroy()
        self._action_clients.clear()
        self._stop.set()
        self.executor.shutdown(timeout_sec=2.0)
        self._thread.join(timeout=2.0)
        with contextlib.suppress(Exception):
            self.provider_node.destroy_node()
