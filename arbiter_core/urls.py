"""The console's server URLs: parsed once, checked before anything starts, one-line errors.

``ws://`` and ``wss://`` for rosbridge, ``http://`` and ``https://`` for the tracker; host, port and
path are all kept. A token is never sent in clear to another machine: with a token, a non-loopback
host needs ``wss://``/``https://`` (or an SSH tunnel, which makes the host loopback).
"""

from __future__ import annotations

from dataclasses import dataclass
from urllib.parse import urlsplit

from .auth import SSH_HINT, is_loopback

DEFAULT_ROSBRIDGE = "ws://127.0.0.1:9090"
DEFAULT_TRACKER_PORT = 8085
ROSBRIDGE_SCHEMES = {"ws": 80, "wss": 443}
TRACKER_SCHEMES = {"http": 80, "https": 443}


class UrlError(ValueError):
    """A URL the console cannot use, with the reason in one line."""


@dataclass(frozen=True, slots=True)
class Endpoint:
    scheme: str
    host: str
    port: int
    path: str  # "/" when none was given

    @property
    def secure(self) -> bool:
        return self.scheme in ("wss", "https")

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{self.scheme}://{host}:{self.port}{self.path}"


def _parse(text: str, what: str, schemes: dict[str, int], default_port: int | None) -> Endpoint:
    try:
        parts = urlsplit(text)
        port = parts.port
    except ValueError as exc:
        raise UrlError(f"{what} {text!r}: {exc}") from None
    if parts.scheme not in schemes:
        wanted = " or ".join(f"{s}://" for s in schemes)
        raise UrlError(f"{what} must start with {wanted}, got {text!r}")
    if not parts.hostname:
        raise UrlError(f"{what} {text!r} has no host")
    if parts.query or parts.fragment:
        raise UrlError(f"{what} {text!r}: no query or fragment, please (the token goes in --token-file)")
    if port == 0:
        raise UrlError(f"{what} {text!r}: port 0 is not a server's port")
    if port is None:
        port = default_port if default_port is not None else schemes[parts.scheme]
    return Endpoint(parts.scheme, parts.hostname, port, parts.path or "/")


def rosbridge_endpoint(text: str, what: str = "--rosbridge") -> Endpoint:
    """``ws://host[:port][/path]`` or ``wss://…``; the port defaults to 9090 (rosbridge's). ``what``
    starts an error's message."""
    return _parse(text, what, ROSBRIDGE_SCHEMES, 9090)


def tracker_endpoint(text: str, what: str = "--tracker") -> Endpoint:
    """``http://host[:port][/path]`` or ``https://…``; the port defaults to 8085 (the tracker's)."""
    return _parse(text, what, TRACKER_SCHEMES, DEFAULT_TRACKER_PORT)


def tracker_beside(rosbridge: Endpoint) -> Endpoint:
    """The tracker a rosbridge URL implies: the same host on 8085, https when the bridge is wss."""
    return Endpoint("https" if rosbridge.secure else "http", rosbridge.host, DEFAULT_TRACKER_PORT, "/")


def check_token_transport(endpoint: Endpoint, flag: str, token: str | None) -> None:
    """Refuse to send a token in clear to another machine."""
    if token is None or endpoint.secure or is_loopback(endpoint.host):
        return
    secure = "wss://" if endpoint.scheme == "ws" else "https://"
    raise UrlError(
        f"{flag} {endpoint.url}: a token is never sent in clear to another machine; "
        f"use {secure} or {SSH_HINT}"
    )
