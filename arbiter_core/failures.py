"""Why a connection failed, in words an operator acts on (pure: exception names and texts in, a line out).

The rosbridge link and the tracker poller both say it on screen with the URL, not only in the log:
connection refused, DNS failure, TLS failure (certificate), token rejected, wrong path.
"""

from __future__ import annotations

import re

TLS_HINT = "TLS failure: the server's certificate is not trusted (a private CA? pass --ca-file)"
TOKEN_HINT = "token rejected: check --token-file / $ARBITER_TOKEN"


def connect_failure(kind: str, text: str) -> str:
    """A failed TCP/TLS connection, from the exception's class name and message."""
    low = f"{kind} {text}".lower()
    if "certificate" in low or "ssl" in low or "tls" in low:
        return TLS_HINT if "verif" in low or "certificate" in low else f"TLS failure: {text or kind}"
    if "refused" in low:
        return "connection refused"
    if (
        "dns" in low
        or "name or service not known" in low
        or "nodename nor servname" in low
        or ("getaddrinfo" in low)
    ):
        return "DNS lookup failed (unknown host)"
    if "timeout" in low or "timed out" in low:
        return "timed out"
    if "unreachable" in low:
        return "network unreachable"
    return f"cannot connect ({kind}{': ' + text if text else ''})"[:160]


def close_failure(code: int | None, reason: str | None) -> str | None:
    """A WebSocket that opened and closed, or whose upgrade the server refused; None: nothing to say
    (a normal close, or a dropped link the keep-alive reports as such)."""
    reason = reason or ""
    if code == 1008 or re.search(r"\b40[13]\b", reason):
        return TOKEN_HINT + (f" ({reason})" if reason else "")
    # autobahn words it "WebSocket connection upgrade failed [404]: Not Found" (older: "(404 - …)")
    status = re.search(r"upgrade failed \[(\d{3})\]", reason) or re.search(r"\((\d{3}) - ", reason)
    if status:
        http = int(status.group(1))
        if http == 404:
            return "HTTP 404: wrong path, or not a rosbridge server there"
        return f"the WebSocket upgrade was refused (HTTP {http})"
    if "certificate" in reason.lower() or "ssl" in reason.lower():
        return TLS_HINT
    return None


def http_failure(status: int) -> str:
    if status in (401, 403):
        return f"{TOKEN_HINT} (HTTP {status})"
    if status == 404:
        return "HTTP 404: wrong path, or not an arbiter latency tracker there"
    return f"HTTP {status}"
