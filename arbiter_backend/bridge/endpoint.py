"""The rosbridge endpoint's connections: a client's frames in, through the dispatch table
(``ops.py``) to the room that handles them, its writer and liveness tasks (``wire.py``), and its state
dropped when the socket closes (its subscriptions, advertisements, provided services and actions,
calls and goals).

Unlike the stock ROS 2 server, every bad frame is answered with a ``status`` frame naming the problem
(and the request's ``id``), and the connection stays open; an op that fails unexpectedly is logged and
answered the same way. A frame over ``--max-frame`` (1 MiB) gets a status error; over 16 MiB aiohttp
closes with 1009. A binary frame whose first byte is a CBOR map's is a CBOR request, turned into the
JSON form first (``cborenc.decode``).
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
from ..bus import Bus, GraphBus
from ..topicwatch import TopicFilter
from . import ops, wire
from .actions import ActionRoom
from .client import CLIENT_QUEUE, Client
from .encoding import Encoder
from .exposure import Exposure
from .frames import BRIDGE_NODE_NAME, DECODER, MAX_FRAME_BYTES, TRANSPORT_MAX_FRAME, BadFrame
from .services import ServiceRoom
from .session import SessionRoom
from .topics import TopicRoom
from .wire import WS_PING_S

log = logging.getLogger(__name__)


class RosbridgeEndpoint:
    """The connections: each client's frames in (JSON or CBOR, authenticated first where a token is
    required) through the dispatch table to its room, its writer and liveness tasks, its state dropped
    when the socket closes."""

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
        namespace: str = "",
        node: str = BRIDGE_NODE_NAME,
    ) -> None:
        self.bus = bus
        self.paced_wait = paced_wait  # seconds a slow client's big frame may hold a small one (pacing)
        self.heartbeat = heartbeat or None  # seconds between pings to a silent client; None: no pings
        self.max_frame = max_frame
        self.client_queue = client_queue
        self.clients: set[Client] = set()
        self.errors = 0
        # what a client may reach (rosbridge_server's topics_glob / services_glob); None: everything
        # and where its relative names resolve: under the bridge node's namespace, as rosbridge's node
        exposure = Exposure(expose_topics, expose_services, expose_actions, namespace, node)
        # ROS mode: the rest of the graph (rosapi, any service), and rclpy servers for what clients
        # provide and an action client for the goals they send (ros/graph.py, ros/interfaces.py)
        on_graph = bus if isinstance(bus, GraphBus) else None
        graph = None if on_graph is None else on_graph.graph
        # the endpoint's own services (rosapi), by name
        distro = graph.distro() if graph is not None else ""
        self.services = rosapi.bus_handlers(bus, exposure.topic_ok, exposure.resolve, distro)
        self.services.update(services or {})
        interfaces = None if on_graph is None else on_graph.interfaces
        self.topic_room = TopicRoom(bus, exposure, Encoder(bus), self.clients, client_queue)
        self.service_room = ServiceRoom(graph, interfaces, exposure, self.services)
        self.action_room = ActionRoom(interfaces, exposure)
        self.session = SessionRoom(token, self._error)
        self._ops = ops.table(self.topic_room, self.service_room, self.action_room, self.session)
        # what clients provide (advertise_service, advertise_action), by name; one provider per name
        self.provided_services = self.service_room.provided
        self.provided_actions = self.action_room.provided

    # -- connection lifecycle ------------------------------------------------------------
    async def handle(self, request: web.Request) -> web.StreamResponse:
        authenticated = self.session.handshake(request)
        if authenticated is None:
            return web.json_response({"error": "wrong token", "status": 401}, status=401)
        # pings are answered and sent here (wire.liveness), not by aiohttp: its heartbeat allows a pong half
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
