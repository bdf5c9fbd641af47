"""The tracker's HTTP API (port 8085): ``GET /api/latency``, ``/api/health`` and ``/api/topics``, JSON."""

from __future__ import annotations

import asyncio
import json
from collections.abc import Callable
from typing import Any, Protocol

from aiohttp import web
from aiohttp.typedefs import Handler

from arbiter_core import auth
from arbiter_core.hostclock import HostClock
from arbiter_core.timesync import TimeSync

from .tracker import DEFAULT_LIMIT, LatencyTracker


def _json(body: Any, status: int = 200) -> web.Response:
    return web.Response(
        text=json.dumps(body, allow_nan=False, separators=(",", ":")),
        status=status,
        content_type="application/json",
    )


class TopicSource(Protocol):
    """The topic monitor of the transport (``topicwatch``): the body of ``GET /api/topics``."""

    def answer(self) -> dict[str, Any]: ...


class BadQuery(ValueError):
    pass


class AutonomySource(Protocol):
    """The robot-side autonomy (``autonomy.AutonomyService``): what ``/api/autonomy`` drives."""

    def start(self, raw: Any) -> dict[str, Any]: ...
    def stop(self) -> dict[str, Any]: ...
    def status(self) -> dict[str, Any]: ...


def _error(status: int, message: str) -> web.Response:
    return _json({"error": message, "status": status}, status)


@web.middleware
async def json_errors(request: web.Request, handler: Handler) -> web.StreamResponse:
    try:
        return await handler(request)
    except web.HTTPMethodNotAllowed as exc:
        resp = _error(405, f"method {request.method} not allowed on {request.path}")
        resp.headers["Allow"] = ", ".join(sorted(exc.allowed_methods))
        return resp
    except web.HTTPNotFound:
        return _error(404, f"no such endpoint: {request.path}")
    except web.HTTPException as exc:
        return _error(exc.status, exc.reason)


def bearer_required(token: str) -> Any:
    @web.middleware
    async def check(request: web.Request, handler: Handler) -> web.StreamResponse:
        if not auth.token_matches(auth.bearer(request.headers.get("Authorization")), token):
            resp = _error(401, "missing or wrong bearer token (Authorization: Bearer TOKEN)")
            resp.headers["WWW-Authenticate"] = 'Bearer realm="arbiter"'
            return resp
        return await handler(request)

    return check


def make_app(
    tracker: LatencyTracker,
    token: str | None = None,
    topics: TopicSource | None = None,
    host_clock: HostClock | None = None,
    bridge: Callable[[], dict[str, Any]] | None = None,
    autonomy: AutonomySource | None = None,
    workers: Callable[[], list[dict[str, Any]]] | None = None,
    fleet: Callable[[], dict[str, Any]] | None = None,
) -> web.Application:
    """``bridge``: the rosbridge endpoint's figures (clients, frames dropped per topic), added to
    ``/api/health`` as its ``bridge`` key. ``autonomy``: the robot-side controller ``/api/autonomy``
    starts (POST), stops (DELETE) and reports (GET); None: 403 (the backend runs without
    ``--autonomy``: nothing that moves the robot is reachable). ``workers``: the backend's long-lived
    workers (``supervise.Supervisor.workers``), added to ``/api/health`` as its ``workers`` key; when one
    is ``failed``, ``status`` is ``degraded`` and ``failed_workers`` names them. ``fleet``: with
    ``--zenoh``, the fleet link's state (``fleet.LinkHealth``), added as its ``fleet`` key."""
    clock = HostClock() if host_clock is None else host_clock

    def _int(request: web.Request, name: str, lo: int, hi: int) -> int | None:
        raw = request.query.get(name)
        if raw is None:
            return None
        try:
            value = int(raw)
        except ValueError:
            raise BadQuery(f"{name} must be an integer, got {raw[:40]!r}") from None
        if not lo <= value <= hi:
            raise BadQuery(f"{name} must be between {lo} and {hi}")
        return value

    async def latency(request: web.Request) -> web.Response:
        try:
            limit = _int(request, "limit", 0, tracker.max_records)
            since = _int(request, "since", 0, 2**63 - 1)
        except BadQuery as exc:
            return _error(400, str(exc))
        if limit is None:
            limit = min(DEFAULT_LIMIT, tracker.max_records)
        text = tracker.latency_response_text(limit, since)
        return web.Response(text=text, content_type="application/json")

    async def health(request: web.Request) -> web.Response:
        body = tracker.health()
        # additive: is this host's clock synchronised, and to what error (probed off the loop, cached)
        body["time_sync"] = (await asyncio.to_thread(clock.read)).to_dict()
        if bridge is not None:
            body = {**body, "bridge": bridge()}
        if fleet is not None:
            body = {**body, "fleet": fleet()}
        if workers is not None:
            listed = workers()
            body = {**body, "workers": listed}
            failed = [w["name"] for w in listed if w["state"] == "failed"]
            if failed:  # a worker given up (supervise.py): loud, at the top
                body["status"], body["failed_workers"] = "degraded", failed
        return _json(body)

    async def topic_figures(request: web.Request) -> web.Response:
        if topics is None:
            return _error(404, "this backend watches no topics")
        return _json(topics.answer())

    async def autonomy_route(request: web.Request) -> web.Response:
        if autonomy is None:
            return _error(403, "autonomy is off: start the backend with --autonomy to drive from it")
        if request.method == "GET":
            return _json(autonomy.status())
        if request.method == "DELETE":
            return _json(autonomy.stop())
        body = await request.content.read(MAX_BODY + 1)
        if len(body) > MAX_BODY:
            return _error(413, f"the body is over {MAX_BODY} bytes")
        try:
            raw = json.loads(body, parse_constant=_no_constant)
        except ValueError as exc:
            return _error(400, f"the body is not JSON: {exc}")
        try:
            return _json(autonomy.start(raw))
        except RuntimeError as exc:
            return _error(409, str(exc))
        except ValueError as exc:
            return _error(400, str(exc))

    middlewares = [json_errors] if token is None else [json_errors, bearer_required(token)]
    app = web.Application(middlewares=middlewares)
    app.router.add_get("/api/latency", latency)

    async def probe_early(app: web.Application) -> None:
        # the first probe can take up to a second or two (a chronyc with no daemon to talk to): start
        # it with the server, so that the first /api/health seldom waits for it
        pending.append(asyncio.get_running_loop().run_in_executor(None, clock.read))

    pending: list[asyncio.Future[TimeSync]] = []

    app.on_startup.append(probe_early)
    app.router.add_get("/api/health", health)
    app.router.add_get("/api/topics", topic_figures)
    for method in ("GET", "POST", "DELETE"):
        app.router.add_route(method, "/api/autonomy", autonomy_route)
    return app


MAX_BODY = 4096


def _no_constant(token: str) -> Any:
    raise ValueError(f"{token} is not a number JSON allows")
