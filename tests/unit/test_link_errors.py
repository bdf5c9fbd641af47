"""Connection failures in words an operator acts on."""

import pytest

from arbiter_core.failures import TLS_HINT, TOKEN_HINT, close_failure, connect_failure, http_failure


@pytest.mark.parametrize(
    ("kind", "text", "starts"),
    [
        (
            "ConnectionRefusedError",
            "Connection was refused by other side: 111: Connection refused.",
            "connection refused",
        ),
        ("DNSLookupError", "DNS lookup failed: address 'nope.invalid' not found", "DNS lookup failed"),
        ("ConnectError", "[Errno -2] Name or service not known", "DNS lookup failed"),
        (
            "Error",
            "[('SSL routines', '', 'certificate verify failed')]",
            "TLS failure: the server's certificate",
        ),
        ("TCPTimedOutError", "TCP connection timed out", "timed out"),
        ("WeirdError", "boom", "cannot connect (WeirdError: boom)"),
    ],
)
def test_connect_failures(kind, text, starts):
    assert connect_failure(kind, text).startswith(starts)


def test_close_failures():
    assert close_failure(1008, "authentication required").startswith(TOKEN_HINT)
    assert close_failure(
        1006, "connection was closed uncleanly (WebSocket connection upgrade failed (404 - NotFound))"
    ) == ("HTTP 404: wrong path, or not a rosbridge server there")
    assert close_failure(1006, "upgrade failed (401 - Unauthorized)").startswith(TOKEN_HINT)
    said = 'connection was closed uncleanly ("WebSocket connection upgrade failed [404]: Not Found")'
    assert close_failure(1006, said).startswith("HTTP 404: wrong path")
    assert close_failure(1006, "WebSocket connection upgrade failed [401]: Unauthorized").startswith(
        TOKEN_HINT
    )
    assert close_failure(1000, None) is None  # a normal close: nothing to say
    assert close_failure(1006, "peer dropped the TCP connection") is None
    assert close_failure(1006, "SSL handshake failed") == TLS_HINT


def test_http_failures():
    assert http_failure(401).startswith(TOKEN_HINT) and "401" in http_failure(401)
    assert http_failure(404).startswith("HTTP 404: wrong path")
    assert http_failure(503) == "HTTP 503"
