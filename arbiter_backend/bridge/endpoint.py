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
import logging
from typing import Any

from aiohttp import WSMsgType, web

from arbiter_core import auth
from arbiter_core.msgtypes import MessageError

from .. import cborenc, pacing, rosapi
from ..bus import Bus
from ..topicwatch import TopicFilter
from . import ops, wire
from .actions import ActionRoom
from .client import CLIENT_QUEUE, Client
from .encoding import Encoder
from .exposure import Exposure
from .frames import DECODER, MAX_FRAME_BYTES, TRANSPORT_MAX_FRAME, BadFrame, dumps
from .services import ServiceRoom
from .session import SessionRoom
from .topics import TopicRoom
from .wire import WS_PING_S

log = logging.getLogger(__name__)

_dumps = dumps


class RosbridgeEndpoint:
    def __init__(
        self,
        bus: Bus,
        max_frame: int = MAX_FRAME_BYTES,
        client_queue: int = CLIENT_QUEUE,
        services: dict[str, rosapi.Handler] | None = None,
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
        self.max_frame = max_frame
        self.client_queue = client_queue
        self.clients: set[Client] = set()
        self.errors = 0
        # what a client may reach (rosbridge_server's topics_glob / services_glob); None: everything
        self.exposure = Exposure(expose_topics, expose_services, expose_actions)
        self.topic_room = TopicRoom(bus, self.exposure, Encoder(bus), self.clients, client_queue)
        # the endpoint's own services (rosapi), by name
        self.services = rosapi.bus_handlers(bus, self.exposure.topic_ok)
        if services:
            self.services.update(services)
        # ROS mode: rclpy servers for what clients provide, an action client for goals (ros/interfaces.py)
        self.interfaces: Any = getattr(bus, "interfaces", None)
        self.service_room = ServiceRoom(bus, self.interfaces, self.exposure, self.services)
        self.action_room = ActionRoom(self.interfaces, self.exposure)
        # what clients provide (advertise_service, advertise_action), by name; one provider per name
        self.provided_services = self.service_room.provided
        self.provided_actions = self.action_room.provided
        self.session = SessionRoom(token, self._error)
        self._ops = ops.table(self.topic_room, self.service_room, self.action_room, self.session)

    # -- connection lifecycle ------------------------------------------------------------
    async def handle(self, request: web.Request) -> web.StreamResponse:
        authenticated = self.session.handshake(request)
        if authenticated is None:
            return web.json_response({"error": "wrong token", "status": 401}, status=401)
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
            deadline = loop.call_later(auth.AUTH_DEADLINE_S, self.session.deadline, client)
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

    def _drop_client(self, client: Client) -> None:
        client.closed = True
        self.action_room.cancel_goals(client)
        for call in list(client.calls):
            call.cancel()
        self.service_room.provided.leave(client)
        self.action_room.provided.leave(client)
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
            self.session.authenticate_text(client, text)
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
            self.session.authenticate(client, frame)
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


def make_app(endpoint: RosbridgeEndpoint) -> web.Application:
    app = web.Application()
    app.router.add_get("/", endpoint.handle)
    return app
