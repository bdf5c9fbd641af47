"""A rosbridge v2 WebSocket endpoint on the in-process topic bus (aiohttp).

Ops: advertise, unadvertise, publish, subscribe (throttle_rate, queue_length, compression
png/cbor/cbor-raw, fragment_size), unsubscribe, call_service, set_level, auth, and services and actions
both ways: advertise_service / service_response / unadvertise_service, advertise_action /
action_feedback / action_result / unadvertise_action (a client provides; ``provided.py``), and
send_action_goal / cancel_action_goal. ``call_service`` reaches, in this order: a service another
client provides; the endpoint's rosapi (/rosapi/topics, topic_type, topics_for_type, and the parameter
services, in memory on the embedded bus; in ROS mode ``rosapi.py`` from the live graph); in ROS mode any
service on the graph (``RosBus.call_service``). In ROS mode a provided service or action is also an
rclpy server on the graph, and a goal reaches any action server there (``ros/interfaces.py``). Calls
and goals run beside the client's other frames, never holding them, and always end: a call within its
``timeout`` (default 10 s), a goal when its server or provider ends it, cancels it, or goes away.
Unlike the real ROS 2 server, every bad frame is answered with a ``status`` frame naming the problem
(and the request's ``id``), and the connection stays open.

Liveness (``--ws-ping``): a client that has sent nothing for ``WS_PING_S`` is pinged (again
every ``WS_PING_S`` while it stays silent), and dropped when nothing at all, pong or frame, has
come from it for ``DEAD_AFTER`` pings' time (20 s by default), which frees its subscriptions and
advertisements. A client busy elsewhere that does not read its socket for 10 s is kept: its pong
waits behind the frames queued for it, and it answers once it reads again (the stock server does
not ping at all). The console finds a dead link on its side with its own pings (1 s, 2 s timeout).

Outgoing frames wait in one bounded queue per (client, topic) (``Outbox``), plus one for the
client's replies (status, service_response), which go first. Each client's writer task takes
the topics with something to send in turn (round-robin; a turn sends up to ``TURN_BYTES``, at
least one message), and awaits aiohttp's drain after each write, so a client takes frames as
fast as its socket drains and no faster. A big topic (camera frames) therefore never starves a
small one: a small message waits for at most the one big frame being written. A full queue
drops its oldest frame (counted per topic, logged, and in ``/api/health``); a slow client loses
old frames of the topic that overflows, never another topic's messages or their order, and never
blocks the bus or the other clients. A client that lags has its big frames paced below the rate it
reads at (``pacing``), so the buffers a small message waits behind stay nearly empty. Per-client state
is dropped when the socket closes.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import logging
from collections.abc import Callable
from typing import Any

from aiohttp import WSMsgType, web

from arbiter_core import auth
from arbiter_core.msgtypes import MessageError, normalize_type

from .. import cborenc, pacing
from ..bus import Bus
from ..provided import (
    FINAL_STATUSES,
    PROVIDER_TIMEOUT_S,
    STATUS_ABORTED,
    STATUS_UNKNOWN,
    CallFailed,
    ProvidedAction,
    ProvidedService,
)
from ..topicwatch import TopicFilter
from . import frames, wire
from .client import CLIENT_QUEUE, LEVELS, Client
from .encoding import Encoder
from .exposure import Exposure
from .frames import DECODER, MAX_FRAME_BYTES, TRANSPORT_MAX_FRAME, BadFrame, dumps
from .topics import TopicRoom
from .wire import WS_PING_S

log = logging.getLogger(__name__)

SERVICE_TIMEOUT_S = 10.0  # a call_service to a ROS service without a "timeout" field
MAX_SERVICE_TIMEOUT_S = 600.0
_dumps = dumps


class RosbridgeEndpoint:
    def __init__(
        self,
        bus: Bus,
        max_frame: int = MAX_FRAME_BYTES,
        client_queue: int = CLIENT_QUEUE,
        services: dict[str, Callable[[Any], dict[str, Any]]] | None = None,
        expose_topics: TopicFilter | None = None,
        expose_services: TopicFilter | None = None,
        expose_actions: TopicFilter | None = None,
        heartbeat: float | None = WS_PING_S,
        token: str | None = None,
        paced_wait: float | None = pacing.WAIT_S,
    ) -> None:
        self.bus = bus
        self.paced_wait = paced_wait  # seconds a slow client's big frame may hold a small one (pacing)
        self.heartbeat = heartbeat or None  # seconds between pings to a silent client; None: no pings
        self.token = token
        self.refused = 0  # connections refused for a missing or wrong token
        self.max_frame = max_frame
        self.client_queue = client_queue
        self.clients: set[Client] = set()
        self.errors = 0
        # what a client may reach (rosbridge_server's topics_glob / services_glob); None: everything
        self.exposure = Exposure(expose_topics, expose_services, expose_actions)
        self.topic_room = TopicRoom(bus, self.exposure, Encoder(bus), self.clients, client_queue)
        self.services: dict[str, Callable[[Any], dict[str, Any]]] = {
            "/rosapi/topics": self._svc_topics,
            "/rosapi/topic_type": self._svc_topic_type,
            "/rosapi/topics_for_type": self._svc_topics_for_type,
        }
        if services:
            self.services.update(services)
        # what clients provide (advertise_service, advertise_action), by name; one provider per name
        self.provided_services: dict[str, ProvidedService] = {}
        self.provided_actions: dict[str, ProvidedAction] = {}
        # ROS mode: rclpy servers for those, an action client for goals (ros/interfaces.py)
        self.interfaces: Any = getattr(bus, "interfaces", None)
        self._ops: dict[str, Callable[[Client, dict[str, Any]], None]] = {
            "advertise": self.topic_room.advertise,
            "unadvertise": self.topic_room.unadvertise,
            "publish": self.topic_room.publish,
            "subscribe": self.topic_room.subscribe,
            "unsubscribe": self.topic_room.unsubscribe,
            "call_service": self._call_service,
            "advertise_service": self._advertise_service,
            "unadvertise_service": self._unadvertise_service,
            "service_response": self._service_response,
            "send_action_goal": self._send_action_goal,
            "cancel_action_goal": self._cancel_action_goal,
            "advertise_action": self._advertise_action,
            "unadvertise_action": self._unadvertise_action,
            "action_feedback": self._action_feedback,
            "action_result": self._action_result,
            "set_level": self._set_level,
            "auth": lambda client, frame: None,  # authenticated already, or no token required
        }

    # -- connection lifecycle ------------------------------------------------------------
    async def handle(self, request: web.Request) -> web.StreamResponse:
        authenticated = self.token is None
        if not authenticated:
            assert self.token is not None
            given = request.query.get("token") or auth.bearer(request.headers.get("Authorization"))
            if given is not None:
                if not auth.token_matches(given, self.token):
                    self.refused += 1
                    log.warning("refused a WebSocket client from %s: wrong token", request.remote)
                    return web.json_response({"error": "wrong token", "status": 401}, status=401)
                authenticated = True
        # pings are answered and sent here (_liveness), not by aiohttp: its heartbeat allows a pong half
        # the interval, which drops a client that stops reading for a second behind a camera stream
        ws = web.WebSocketResponse(max_msg_size=TRANSPORT_MAX_FRAME, autoping=False)
        await ws.prepare(request)
        client = Client(ws, self.client_queue, request.remote, self.paced_wait)
        client.authenticated = authenticated
        self.clients.add(client)
        loop = asyncio.get_running_loop()
        writer = loop.create_task(wire.writer(client))
        client.last_rx = loop.time()
        liveness = None
        if self.heartbeat is not None and request.transport is not None:
            liveness = loop.create_task(wire.liveness(client, request.transport, self.heartbeat))
        deadline = None
        if not authenticated:
            deadline = loop.call_later(auth.AUTH_DEADLINE_S, self._auth_timeout, client)
        log.info("client %d connected from %s", client.id, request.remote)
        sock = request.transport.get_extra_info("socket") if request.transport is not None else None
        wire.limit_unsent(sock)
        try:
            async for msg in ws:
                client.last_rx = loop.time()
                if msg.type == WSMsgType.PING:
                    await ws.pong(msg.data)
                    continue
                if msg.type == WSMsgType.PONG:
                    continue
                if client.kick is not None:
                    pass  # being closed: nothing more is read into the robot
                elif msg.type == WSMsgType.TEXT:
                    self.handle_frame(client, msg.data)
                elif msg.type == WSMsgType.BINARY:
                    if cborenc.is_cbor(msg.data):
                        self.handle_cbor(client, msg.data)
                        continue
                    try:
                        text = msg.data.decode("utf-8")
                    except UnicodeDecodeError:
                        self._error(client, "binary frame is neither UTF-8 JSON text nor a CBOR map")
                    else:
                        self.handle_frame(client, text)
                elif msg.type == WSMsgType.ERROR:
                    log.info("client %d socket error: %s", client.id, ws.exception())
                    break
                # After the frame reached the tracker, not before: on loopback the ACK this sends is
                # processed inline, ~45 µs a command would otherwise wait (bench/latency.py, issue 16).
                wire.quick_ack(sock)
        finally:
            if deadline is not None:
                deadline.cancel()
            self._drop_client(client)
            if liveness is not None:
                liveness.cancel()
            writer.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await writer
            log.info(
                "client %d disconnected (dropped %d outgoing frames%s)",
                client.id,
                client.dropped,
                "".join(f", {n} of {t}" for t, n in sorted(client.dropped_by_topic.items())),
            )
        return ws

    def _refuse(self, client: Client, reason: str) -> None:
        """Answer with an error, then close (1008, policy violation) once the answer is sent."""
        self.refused += 1
        self._error(client, reason)
        client.kick = (1008, reason)
        client.wakeup.set()

    def _auth_timeout(self, client: Client) -> None:
        if not client.authenticated and client.kick is None and not client.closed:
            self._refuse(client, f"authentication required within {auth.AUTH_DEADLINE_S:.0f} s")

    def _authenticate(self, client: Client, text: str) -> None:
        """The first frame of a client that brought no token in its handshake must be ``auth``."""
        try:
            frame = DECODER.decode(text) if len(text) <= 4096 else None
        except (ValueError, RecursionError):
            frame = None
        self._authenticate_frame(client, frame)

    def _authenticate_frame(self, client: Client, frame: Any) -> None:
        if not isinstance(frame, dict) or frame.get("op") != "auth":
            self._refuse(client, 'authentication required: send {"op": "auth", "mac": TOKEN} first')
            return
        assert self.token is not None
        given = frame.get("mac", frame.get("token"))
        if not auth.token_matches(given, self.token):
            self._refuse(client, "authentication failed: wrong token")
            return
        client.authenticated = True

    def _drop_client(self, client: Client) -> None:
        client.closed = True
        for cancel_goal in list(client.goals.values()):
            cancel_goal()  # a goal does not go on for a client that is gone
        client.goals.clear()
        for call in list(client.calls):
            call.cancel()
        for svc in [s for s in self.provided_services.values() if s.provider is client]:
            self._retire_service(svc, f"Service {svc.name}: its provider disconnected")
        for act in [a for a in self.provided_actions.values() if a.provider is client]:
            self._retire_action(act, f"Action {act.name}: its provider disconnected")
        self.topic_room.leave(client)
        self.clients.discard(client)

    def stats(self) -> dict[str, Any]:
        """The endpoint's clients and their outgoing queues (``/api/health``'s ``bridge``)."""
        dropped: dict[str, int] = {}
        for client in self.clients:
            for topic, n in client.dropped_by_topic.items():
                dropped[topic] = dropped.get(topic, 0) + n
        return {
            "clients": len(self.clients),
            "errors": self.errors,
            "dropped": dropped,  # frames dropped for slow clients, by topic (the clients connected now)
            "per_client": [c.stats() for c in sorted(self.clients, key=lambda c: c.id)],
        }

    async def close_all(self) -> None:
        for client in list(self.clients):
            with contextlib.suppress(Exception):
                await client.ws.close()

    # -- frames ------------------------------------------------------------------------------
    def _error(self, client: Client, msg: str, req_id: Any = None) -> None:
        self.errors += 1
        client.status("error", msg, req_id)

    def handle_frame(self, client: Client, text: str) -> None:
        if not client.authenticated:
            self._authenticate(client, text)
            return
        if len(text) > self.max_frame:
            self._error(client, f"frame of {len(text)} bytes exceeds the {self.max_frame}-byte limit")
            return
        try:
            frame = DECODER.decode(text)
        except BadFrame as exc:
            self._error(client, f"invalid JSON: {exc}")
            return
        except (ValueError, RecursionError) as exc:
            self._error(client, f"invalid JSON: {str(exc)[:200]}")
            return
        if not isinstance(frame, dict):
            self._error(client, f"a frame must be a JSON object, got {type(frame).__name__}")
            return
        self._dispatch(client, frame)

    def handle_cbor(self, client: Client, data: bytes) -> None:
        """A binary frame holding a CBOR map: the same request as its JSON form (``cborenc.decode``)."""
        if len(data) > self.max_frame:
            self._error(client, f"frame of {len(data)} bytes exceeds the {self.max_frame}-byte limit")
            return
        try:
            frame = cborenc.decode(data)
        except cborenc.CborError as exc:
            self._error(client, str(exc), exc.req_id)
            return
        if not client.authenticated:
            self._authenticate_frame(client, frame)
            return
        self._dispatch(client, frame)

    def _dispatch(self, client: Client, frame: dict[str, Any]) -> None:
        req_id = frame.get("id")
        if isinstance(req_id, (dict, list)):
            req_id = None
        op = frame.get("op")
        if not isinstance(op, str):
            self._error(client, "frame has no string field 'op'", req_id)
            return
        handler = self._ops.get(op)
        if handler is None:
            self._error(client, f"unknown operation {op[:60]!r}", req_id)
            return
        try:
            handler(client, frame)
        except (BadFrame, MessageError) as exc:
            self._error(client, f"{op}: {exc}", req_id)
        except Exception as exc:  # never let one frame take the connection down
            log.exception("op %s failed", op)
            self._error(client, f"{op}: internal error: {type(exc).__name__}", req_id)

    def _call_service(self, client: Client, frame: dict[str, Any]) -> None:
        client.room_for_call()
        service = frames.field(frame, "service", str)
        req_id = frame.get("id")
        reply: dict[str, Any] = {"op": "service_response", "service": service}
        if req_id is not None:
            reply["id"] = req_id
        if not service.startswith("/rosapi/") and not self.exposure.service_ok(service):
            reply.update(
                result=False, values=f"Service {service} is not exposed by this server (--services-glob)"
            )
            client.send(_dumps(reply))
            return
        provided = self.provided_services.get(service)
        if provided is not None:  # a WebSocket client provides it: straight to that client
            timeout = self._timeout(frame, PROVIDER_TIMEOUT_S)
            args = frame.get("args", {})
            if self.interfaces is not None:
                try:
                    args = self.interfaces.values(provided.type_name, "Request", args, path="args")
                except MessageError as exc:
                    reply.update(result=False, values=f"{service}: {exc}")
                    client.send(_dumps(reply))
                    return
            client.track(self._call_provided(client, provided, args, timeout, reply))
            return
        handler = self.services.get(service)
        remote = getattr(self.bus, "call_service", None)
        if handler is None and remote is not None:  # ROS mode: any service on the graph
            timeout = self._timeout(frame, SERVICE_TIMEOUT_S)
            client.track(self._call_remote(client, remote, service, frame.get("args"), timeout, reply))
            return
        if handler is None:
            reply.update(result=False, values=f"Service {service} does not exist")
        else:
            timeout = self._timeout(frame, SERVICE_TIMEOUT_S)
            try:
                values = handler(frame.get("args"))
            except (BadFrame, MessageError, ValueError) as exc:
                reply.update(result=False, values=f"{service}: {exc}")
            else:
                if inspect.isawaitable(values):  # rosapi that asks the graph (parameters)
                    client.track(
                        self._call_remote(client, lambda _s, _a: values, service, None, timeout, reply),
                    )
                    return
                reply.update(result=True, values=values)
        client.send(_dumps(reply))

    def _timeout(self, frame: dict[str, Any], default: float) -> float:
        timeout = frames.field(frame, "timeout", (int, float), required=False)
        timeout = default if timeout is None else float(timeout)
        if not 0 < timeout <= MAX_SERVICE_TIMEOUT_S:
            raise BadFrame(f"timeout must be more than 0 and at most {MAX_SERVICE_TIMEOUT_S:g} s")
        return timeout

    async def _call_provided(
        self, client: Client, provided: ProvidedService, args: Any, timeout: float, reply: dict[str, Any]
    ) -> None:
        try:
            ok, values = await provided.call(args, timeout)
        except CallFailed as exc:
            ok, values = False, str(exc)
        reply.update(result=ok, values=values)
        client.send(_dumps(reply))

    async def _call_remote(
        self,
        client: Client,
        remote: Callable[[str, Any], Any],
        service: str,
        args: Any,
        timeout: float,
        reply: dict[str, Any],
    ) -> None:
        """A call to a ROS service; the answer, or ``result: false`` with why, within ``timeout``. The
        client's other frames are not held meanwhile (the stock server blocks them by default)."""
        try:
            values = await asyncio.wait_for(remote(service, args), timeout)
        except (TimeoutError, asyncio.TimeoutError):  # distinct before Python 3.11 (a Pi with Humble)
            reply.update(result=False, values=f"{service}: no response within {timeout:g} s")
        except (BadFrame, MessageError, ValueError) as exc:
            reply.update(
                result=False, values=str(exc) if str(exc).startswith("Service") else f"{service}: {exc}"
            )
        except Exception as exc:
            log.exception("call to %s failed", service)
            reply.update(result=False, values=f"{service}: {type(exc).__name__}")
        else:
            reply.update(result=True, values=values)
        client.send(_dumps(reply))

    # -- services and actions clients provide (advertise_service, advertise_action) -------------------
    def _advertise_service(self, client: Client, frame: dict[str, Any]) -> None:
        name = frames.name(frame, "service")
        if name.startswith("/rosapi/") or name in self.services:
            raise BadFrame(f"service {name} is the server's own")
        if not self.exposure.service_ok(name):
            raise BadFrame(f"service {name} is not exposed by this server (--services-glob)")
        type_name = frames.interface_type(frame, "type", "srv", self.interfaces)
        svc = ProvidedService(name, type_name, client)
        if self.interfaces is not None:  # on the graph first: if that fails, the old provider stays
            svc.withdraw = self.interfaces.advertise_service(name, type_name, svc.call)
        old = self.provided_services.get(name)
        self.provided_services[name] = svc
        if old is not None:
            self._replaced(client, frame, "service", name, old.provider.id)
            self._retire_service(old, f"Service {name} was advertised again by another provider")
        log.info("client %d provides service %s (%s)", client.id, name, type_name)

    def _replaced(self, client: Client, frame: dict[str, Any], kind: str, name: str, old_id: int) -> None:
        """A second advertisement replaces the first, as rosbridge_server does, with a warning."""
        msg = f"duplicate {kind} advertised: {name} was provided by client {old_id}; replaced"
        log.warning("client %d: %s", client.id, msg)
        client.status("warning", msg, frame.get("id"))

    def _retire_service(self, svc: ProvidedService, reason: str) -> None:
        if self.provided_services.get(svc.name) is svc:
            del self.provided_services[svc.name]
        svc.fail_all(reason)
        if svc.withdraw is not None:
            svc.withdraw()
            svc.withdraw = None

    def _provided_by(self, client: Client, frame: dict[str, Any], kind: str) -> Any:
        name = frames.name(frame, kind)
        table: dict[str, Any] = self.provided_services if kind == "service" else self.provided_actions
        entry = table.get(name)
        if entry is None or entry.provider is not client:
            raise BadFrame(f"{kind} {name} is not advertised by this client")
        return entry

    def _unadvertise_service(self, client: Client, frame: dict[str, Any]) -> None:
        svc = self._provided_by(client, frame, "service")
        self._retire_service(svc, f"Service {svc.name} was unadvertised")
        log.info("client %d no longer provides service %s", client.id, svc.name)

    def _service_response(self, client: Client, frame: dict[str, Any]) -> None:
        svc: ProvidedService = self._provided_by(client, frame, "service")
        req_id = frames.field(frame, "id", str)
        result = frames.field(frame, "result", bool)
        values = frame.get("values", {})
        if result:
            if not isinstance(values, dict):
                raise BadFrame("values must be an object when result is true")
            if self.interfaces is not None:
                try:
                    values = self.interfaces.values(svc.type_name, "Response", values)
                except MessageError as exc:  # the caller learns it now, not at its timeout
                    svc.answer(req_id, False, f"{svc.name}: its provider's response does not fit: {exc}")
                    raise
        if not svc.answer(req_id, result, values):
            raise BadFrame(f"no call to {svc.name} with id {req_id[:80]!r} is waiting for an answer")

    def _advertise_action(self, client: Client, frame: dict[str, Any]) -> None:
        name = self.exposure.action(frame)
        type_name = frames.interface_type(frame, "type", "action", self.interfaces)
        act = ProvidedAction(name, type_name, client, type_given=frame["type"])
        if self.interfaces is not None:
            act.withdraw = self.interfaces.advertise_action(name, type_name, act.start, act.cancel)
        old = self.provided_actions.get(name)
        self.provided_actions[name] = act
        if old is not None:
            self._replaced(client, frame, "action", name, old.provider.id)
            self._retire_action(old, f"Action {name} was advertised again by another provider")
        log.info("client %d provides action %s (%s)", client.id, name, type_name)

    def _retire_action(self, act: ProvidedAction, reason: str) -> None:
        if self.provided_actions.get(act.name) is act:
            del self.provided_actions[act.name]
        act.fail_all(reason)
        if act.withdraw is not None:
            act.withdraw()
            act.withdraw = None

    def _unadvertise_action(self, client: Client, frame: dict[str, Any]) -> None:
        act = self._provided_by(client, frame, "action")
        self._retire_action(act, f"Action {act.name} was unadvertised")
        log.info("client %d no longer provides action %s", client.id, act.name)

    def _action_feedback(self, client: Client, frame: dict[str, Any]) -> None:
        act: ProvidedAction = self._provided_by(client, frame, "action")
        goal_id = frames.field(frame, "id", str)
        values = frames.field(frame, "values", dict)
        if self.interfaces is not None:
            values = self.interfaces.values(act.type_name, "Feedback", values)
        if not act.feedback(goal_id, values):
            raise BadFrame(f"no goal of {act.name} with id {goal_id[:80]!r} is running")

    def _action_result(self, client: Client, frame: dict[str, Any]) -> None:
        act: ProvidedAction = self._provided_by(client, frame, "action")
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

    # -- goals clients send (send_action_goal, cancel_action_goal) -------------------------------------
    def _send_action_goal(self, client: Client, frame: dict[str, Any]) -> None:
        client.room_for_call()
        action = self.exposure.action(frame)
        req_id = frame.get("id")
        if req_id is not None and not isinstance(req_id, (str, int)):
            raise BadFrame("field 'id' must be a string or an integer")
        feedback = frames.field(frame, "feedback", bool, required=False) is True
        if req_id is not None and req_id in client.goals:
            raise BadFrame(f"a goal with id {req_id!r} is running already: give each goal its own id")
        args = frame.get("args", {})
        provided = self.provided_actions.get(action)
        type_name = frames.interface_type(frame, "action_type", "action", self.interfaces)
        if provided is None and self.interfaces is None:
            self._goal_ended(client, action, req_id, STATUS_UNKNOWN, f"Action {action} does not exist", False)
            return
        if self.interfaces is not None:
            args = self.interfaces.values(type_name, "Goal", args, path="args")  # MessageError: status
        ended: list[bool] = []  # the result went out: later feedback is not sent (ROS carries feedback
        # and result on different channels, so the last feedback can arrive after the result)
        on_feedback = None
        if feedback:
            on_feedback = lambda values: ended or self._goal_feedback(client, action, req_id, values)  # noqa: E731
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
        client.send(_dumps(frame))

    def _goal_ended(
        self, client: Client, action: str, req_id: Any, status: int, values: Any, result: bool
    ) -> None:
        if req_id is not None:
            client.goals.pop(req_id, None)
        frame: dict[str, Any] = {"op": "action_result", "action": action, "values": values}
        frame.update(status=status, result=result)
        if req_id is not None:
            frame["id"] = req_id
        client.send(_dumps(frame))

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

    def _cancel_action_goal(self, client: Client, frame: dict[str, Any]) -> None:
        frames.name(frame, "action")
        if "id" not in frame:
            raise BadFrame("missing field 'id' (the id of the goal to cancel)")
        req_id = frame["id"]
        cancel = client.goals.get(req_id) if isinstance(req_id, (str, int)) else None
        if cancel is None:
            raise BadFrame(f"no goal with id {str(req_id)[:80]!r} is running for this client")
        cancel()

    def _set_level(self, client: Client, frame: dict[str, Any]) -> None:
        level = frames.field(frame, "level", str)
        if level not in LEVELS:
            raise BadFrame(f"level must be one of {', '.join(LEVELS)}")
        client.level = level

    # -- rosapi --------------------------------------------------------------------------------
    def _svc_topics(self, args: Any) -> dict[str, Any]:
        topics = [(t, ty) for t, ty in self.bus.topics() if self.exposure.topic_ok(t)]
        return {"topics": [t for t, _ in topics], "types": [ty for _, ty in topics]}

    def _svc_topic_type(self, args: Any) -> dict[str, Any]:
        topic = (
            args.get("topic")
            if isinstance(args, dict)
            else (args[0] if isinstance(args, list) and args else None)
        )
        if not isinstance(topic, str):
            raise BadFrame("args.topic must be a string")
        return {"type": (self.bus.type_of(topic) or "") if self.exposure.topic_ok(topic) else ""}

    def _svc_topics_for_type(self, args: Any) -> dict[str, Any]:
        t = args.get("type") if isinstance(args, dict) else None
        if not isinstance(t, str):
            raise BadFrame("args.type must be a string")
        want = normalize_type(t)
        return {"topics": [t for t, ty in self.bus.topics() if ty == want and self.exposure.topic_ok(t)]}


def make_app(endpoint: RosbridgeEndpoint) -> web.Application:
    app = web.Application()
    app.router.add_get("/", endpoint.handle)
    return app
