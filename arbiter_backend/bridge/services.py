"""Service ops: ``call_service``, and services clients provide (``advertise_service``,
``service_response``, ``unadvertise_service``).

``call_service`` reaches, in this order: a service another client provides (a ``call_service`` frame
to it, ``service_request:<service>:<n>``, answered by its ``service_response``); the endpoint's rosapi
(``rosapi.py``); in ROS mode any service on the graph (``RosGraph.call_service``). A call runs beside
the client's other frames, never holding them, and always ends within its ``timeout`` (default 10 s):
the answer, or ``result: false`` with why. In ROS mode a provided service is also an rclpy service on
the graph (``ros/interfaces.py``), and values are checked against the type's Request and Response.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Callable
from typing import Any

from arbiter_core.msgtypes import MessageError

from .. import rosapi
from ..provided import PROVIDER_TIMEOUT_S, CallFailed, ProvidedService
from . import frames
from .client import Client
from .exposure import Exposure
from .frames import BadFrame, Frame, dumps
from .providers import Providers

log = logging.getLogger(__name__)

SERVICE_TIMEOUT_S = 10.0  # a call_service to a ROS service without a "timeout" field
MAX_SERVICE_TIMEOUT_S = 600.0


def timeout(frame: Frame, default: float) -> float:
    """The call's ``timeout`` (seconds), ``default`` without one."""
    given = frames.field(frame, "timeout", (int, float), required=False)
    seconds = default if given is None else float(given)
    if not 0 < seconds <= MAX_SERVICE_TIMEOUT_S:
        raise BadFrame(f"timeout must be more than 0 and at most {MAX_SERVICE_TIMEOUT_S:g} s")
    return seconds


class ServiceRoom:
    def __init__(
        self, graph: rosapi.Graph | None, interfaces: Any, exposure: Exposure, own: dict[str, rosapi.Handler]
    ) -> None:
        self.graph = graph  # ROS mode: any service on it is reached; None on the embedded bus
        self.interfaces = interfaces  # ROS mode: ros.interfaces.RosInterfaces; None on the embedded bus
        self.exposure = exposure
        self.own = own  # the endpoint's own services (rosapi), by name
        self.provided: Providers[ProvidedService] = Providers("service", exposure.name)

    # -- calls ---------------------------------------------------------------------------------------
    def call_service(self, client: Client, frame: Frame) -> None:
        client.room_for_call()
        given = frames.field(frame, "service", str)
        req_id = frame.get("id")
        reply: dict[str, Any] = {"op": "service_response", "service": given}  # the name as given, as stock
        if req_id is not None:
            reply["id"] = req_id
        try:  # relative names under the bridge's namespace: rosapi/topics is /rosapi/topics in the root
            service = self.exposure.name(frame, "service")
        except BadFrame as exc:
            reply.update(result=False, values=str(exc))
            client.send(dumps(reply))
            return
        if not service.startswith("/rosapi/") and not self.exposure.service_ok(service):
            reply.update(
                result=False, values=f"Service {service} is not exposed by this server (--services-glob)"
            )
            client.send(dumps(reply))
            return
        provided = self.provided.get(service)
        if provided is not None:  # a WebSocket client provides it: straight to that client
            seconds = timeout(frame, PROVIDER_TIMEOUT_S)
            args = frame.get("args", {})
            if self.interfaces is not None:
                try:
                    args = self.interfaces.values(provided.type_name, "Request", args, path="args")
                except MessageError as exc:
                    reply.update(result=False, values=f"{service}: {exc}")
                    client.send(dumps(reply))
                    return
            client.track(self._call_provided(client, provided, args, seconds, reply))
            return
        handler = self.own.get(service)
        if handler is None and self.graph is not None:  # ROS mode: any service on the graph
            seconds = timeout(frame, SERVICE_TIMEOUT_S)
            remote = self.graph.call_service
            client.track(self._call_remote(client, remote, service, frame.get("args"), seconds, reply))
            return
        if handler is None:
            reply.update(result=False, values=f"Service {service} does not exist")
        else:
            seconds = timeout(frame, SERVICE_TIMEOUT_S)
            try:
                values = handler(frame.get("args"))
            except (BadFrame, MessageError, ValueError) as exc:
                reply.update(result=False, values=f"{service}: {exc}")
            except Exception as exc:  # a bug, or the graph changed under it: answered all the same
                log.exception("%s failed", service)
                reply.update(result=False, values=f"{service}: {type(exc).__name__}: {exc}"[:300])
            else:
                if inspect.isawaitable(values):  # rosapi that asks the graph (parameters)
                    client.track(
                        self._call_remote(client, lambda _s, _a: values, service, None, seconds, reply),
                    )
                    return
                reply.update(result=True, values=values)
        client.send(dumps(reply))

    async def _call_provided(
        self, client: Client, provided: ProvidedService, args: Any, seconds: float, reply: dict[str, Any]
    ) -> None:
        try:
            ok, values = await provided.call(args, seconds)
        except CallFailed as exc:
            ok, values = False, str(exc)
        reply.update(result=ok, values=values)
        client.send(dumps(reply))

    async def _call_remote(
        self,
        client: Client,
        remote: Callable[[str, Any], Any],
        service: str,
        args: Any,
        seconds: float,
        reply: dict[str, Any],
    ) -> None:
        """A call to a ROS service; the answer, or ``result: false`` with why, within ``seconds``. The
        client's other frames are not held meanwhile (the stock server blocks them by default)."""
        try:
            values = await asyncio.wait_for(remote(service, args), seconds)
        except (TimeoutError, asyncio.TimeoutError):  # distinct before Python 3.11 (a Pi with Humble)
            reply.update(result=False, values=f"{service}: no response within {seconds:g} s")
        except (BadFrame, MessageError, ValueError) as exc:
            reply.update(
                result=False, values=str(exc) if str(exc).startswith("Service") else f"{service}: {exc}"
            )
        except Exception as exc:
            log.exception("call to %s failed", service)
            reply.update(result=False, values=f"{service}: {type(exc).__name__}")
        else:
            reply.update(result=True, values=values)
        client.send(dumps(reply))

    # -- services clients provide --------------------------------------------------------------------
    def advertise_service(self, client: Client, frame: Frame) -> None:
        name = self.exposure.name(frame, "service")
        if name.startswith("/rosapi/") or name in self.own:
            raise BadFrame(f"service {name} is the server's own")
        if not self.exposure.service_ok(name):
            raise BadFrame(f"service {name} is not exposed by this server (--services-glob)")
        type_name = frames.interface_type(frame, "type", "srv", self.interfaces)
        svc = ProvidedService(name, type_name, client, given=frame["service"])
        if self.interfaces is not None:  # on the graph first: if that fails, the old provider stays
            svc.withdraw = self.interfaces.advertise_service(name, type_name, svc.call)
        self.provided.install(client, frame, svc)

    def service_response(self, client: Client, frame: Frame) -> None:
        svc = self.provided.owned(client, frame)
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
