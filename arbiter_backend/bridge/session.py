"""Who a client is and what it hears: ``auth`` and ``set_level`` (the ``status`` frames it gets).

With a token configured (``arbiter_core.auth``) the WebSocket handshake must carry it (``?token=`` or a
bearer header; a wrong one is answered 401) or the client's first frame must be ``auth`` with it
(``mac``, or ``token``), within ``auth.AUTH_DEADLINE_S``; otherwise a ``status`` error and close 1008.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from aiohttp import web

from arbiter_core import auth

from . import frames
from .client import LEVELS, Client
from .frames import DECODER, BadFrame, Frame

log = logging.getLogger(__name__)


class SessionRoom:
    def __init__(self, token: str | None, error: Callable[[Client, str], None]) -> None:
        self.token = token
        self.error = error  # a status error to the client, counted by the endpoint
        self.refused = 0  # connections refused for a missing or wrong token

    # -- ops ----------------------------------------------------------------------------------------
    def auth(self, client: Client, frame: Frame) -> None:
        """Authenticated already (the first frame is checked before dispatch), or no token required."""

    def set_level(self, client: Client, frame: Frame) -> None:
        level = frames.field(frame, "level", str)
        if level not in LEVELS:
            raise BadFrame(f"level must be one of {', '.join(LEVELS)}")
        client.level = level

    # -- authentication ----------------------------------------------------------------------------
    def handshake(self, request: web.Request) -> bool | None:
        """Whether the handshake authenticated the client (or no token is required); None when it
        brought a wrong token (refused: answer 401)."""
        if self.token is None:
            return True
        given = request.query.get("token") or auth.bearer(request.headers.get("Authorization"))
        if given is None:
            return False
        if not auth.token_matches(given, self.token):
            self.refused += 1
            log.warning("refused a WebSocket client from %s: wrong token", request.remote)
            return None
        return True

    def deadline(self, client: Client) -> None:
        """``auth.AUTH_DEADLINE_S`` after it connected: a client still unauthenticated is refused."""
        if not client.authenticated and client.kick is None and not client.closed:
            self._refuse(client, f"authentication required within {auth.AUTH_DEADLINE_S:.0f} s")

    def authenticate_text(self, client: Client, text: str) -> None:
        """The first frame of a client that brought no token in its handshake must be ``auth``."""
        try:
            frame = DECODER.decode(text) if len(text) <= 4096 else None
        except (ValueError, RecursionError):
            frame = None
        self.authenticate(client, frame)

    def authenticate(self, client: Client, frame: Any) -> None:
        if not isinstance(frame, dict) or frame.get("op") != "auth":
            self._refuse(client, 'authentication required: send {"op": "auth", "mac": TOKEN} first')
            return
        assert self.token is not None
        given = frame.get("mac", frame.get("token"))
        if not auth.token_matches(given, self.token):
            self._refuse(client, "authentication failed: wrong token")
            return
        client.authenticated = True

    def _refuse(self, client: Client, reason: str) -> None:
        """Answer with an error, then close (1008, policy violation) once the answer is sent."""
        self.refused += 1
        self.error(client, reason)
        client.kick = (1008, reason)
        client.wakeup.set()
