"""Who may connect: loopback by default; anything else needs ``--allow-remote`` and a shared token.

The token reaches the servers in one of three ways: the rosbridge protocol's
``auth`` op (``{"op": "auth", "mac": TOKEN}``, the field roslibpy's
``authenticate`` fills; ``token`` is accepted too), a ``?token=`` query
parameter on the WebSocket URL, or an ``Authorization: Bearer TOKEN`` header
(HTTP API and WebSocket handshake). Tokens are compared in constant time.
"""

from __future__ import annotations

import hmac
import ipaddress
import os
from collections.abc import Mapping
from pathlib import Path

TOKEN_ENV = "ARBITER_TOKEN"
MIN_TOKEN_CHARS = 16
AUTH_DEADLINE_S = 5.0  # a WebSocket client without a token in its handshake must send auth this fast

SSH_HINT = "use an SSH tunnel instead (ssh -L 9090:127.0.0.1:9090 -L 8085:127.0.0.1:8085 robot)"


class AuthConfigError(ValueError):
    """The command line asks for an exposure the configuration does not allow."""


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False  # a host name other than localhost may resolve to anything


def load_token(token_file: Path | None, environ: Mapping[str, str] = os.environ) -> str | None:
    """The token from ``--token-file`` (first line) or ``$ARBITER_TOKEN``; None when neither is set."""
    if token_file is not None:
        try:
            text = Path(token_file).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise AuthConfigError(f"cannot read --token-file {token_file}: {exc}") from None
        token = text.splitlines()[0].strip() if text.strip() else ""
    else:
        token = environ.get(TOKEN_ENV, "").strip()
        if not token:
            return None
    if len(token) < MIN_TOKEN_CHARS or not token.isprintable() or " " in token:
        raise AuthConfigError(
            f"the token must be at least {MIN_TOKEN_CHARS} printable characters without spaces "
            "(e.g. python3 -c 'import secrets; print(secrets.token_urlsafe(24))')"
        )
    return token


def check_exposure(host: str, allow_remote: bool, token: str | None) -> None:
    """Refuse to listen beyond loopback without ``--allow-remote`` and a token."""
    if is_loopback(host):
        return
    if not allow_remote:
        raise AuthConfigError(f"refusing to listen on {host} without --allow-remote; {SSH_HINT}")
    if token is None:
        raise AuthConfigError(
            f"--allow-remote needs a token: set ${TOKEN_ENV} or pass --token-file; {SSH_HINT}"
        )


def token_matches(given: object, expected: str) -> bool:
    if not isinstance(given, str):
        return False
    return hmac.compare_digest(given.encode("utf-8", "surrogatepass"), expected.encode("utf-8"))


def bearer(header: str | None) -> str | None:
    """The token of an ``Authorization: Bearer TOKEN`` header, if that is what it is."""
    if not header:
        return None
    scheme, _, value = header.partition(" ")
    if scheme.lower() != "bearer" or not value.strip():
        return None
    return value.strip()
