"""Where the rosbridge link reaches inside Twisted, and inside roslibpy's factory over it: every such
access in one place, each applied only to the Twisted releases it was checked against (``CHECKED``,
major.minor; Twisted is bounded in pyproject.toml), as the console's Textual patches are
(``arbiter_tui/shell/perf``).

- :func:`write_now`: a command frame written straight into a plain TCP socket when nothing is buffered,
  which reads Twisted's private write buffers (``_tempDataBuffer``, ``dataBuffer``). On a release not
  checked, autobahn's ``sendMessage`` (the public path: through Twisted's buffer, a reactor turn later).
- :func:`hook_connection`: the factory's connection events (``startedConnecting``,
  ``clientConnectionFailed``, ``clientConnectionLost``, Twisted's ``ReconnectingClientFactory``
  interface) wrapped on the instance roslibpy made, each calling the original after ours.
- :func:`retry_slowly`, :func:`retry_fast`: that factory's backoff (``delay``, ``factor``, ``maxDelay``).
- :func:`open_protocol`, :func:`handle_op`: roslibpy's factory's ``_proto`` (the open connection's
  protocol, or None) and its protocol's ``_message_handlers``; roslibpy is pinned exactly in pyproject.toml.

``tests/unit/test_twisted_internals.py`` fails on a Twisted release not in ``CHECKED`` (it never skips):
an upgrade shows up as a red test naming the release, never as a private read that silently changed.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from . import wsframe

log = logging.getLogger(__name__)

CHECKED = ("26.10",)  # the Twisted releases (major.minor) whose tcp.Client buffers were read here

_installed: bool | None = None  # set by install(): whether the private reads are used


def release() -> str:
    import twisted

    return str(twisted.__version__)


def checked(version: str | None = None) -> bool:
    """Whether this Twisted release (major.minor) was checked."""
    parts = (release() if version is None else version).split(".")
    return ".".join(parts[:2]) in CHECKED


def install() -> bool:
    """Decide once (the link's start) whether :func:`write_now` may read Twisted's buffers; a release not
    checked is said once in the log and takes the public path."""
    global _installed
    if _installed is None:
        _installed = checked()
        if not _installed:
            log.warning(
                "Twisted %s was not checked (checked: %s): commands go through autobahn's buffer",
                release(), ", ".join(CHECKED),
            )  # fmt: skip
    return _installed


def write_now(proto: Any, payload: bytes) -> None:
    """Send a text frame on the reactor thread: straight into the socket when it is a plain TCP
    socket with nothing buffered (so ordering is kept), otherwise through autobahn and Twisted's
    buffer (TLS, data already queued, or a Twisted release not checked)."""
    from twisted.internet import tcp

    transport = getattr(proto, "transport", None)
    if (
        not _installed
        # only a plain TCP socket: under TLS (a BufferingTLSTransport, or tcp.Client after startTLS)
        # writeSomeData would bypass the encryption (found by the wss:// test)
        or not isinstance(transport, tcp.Client)
        or transport.TLS
        or getattr(proto, "state", None) != getattr(proto, "STATE_OPEN", object())
        or getattr(transport, "_tempDataBuffer", True)
        or getattr(transport, "dataBuffer", True)
    ):
        proto.sendMessage(payload, isBinary=False)
        return
    frame = wsframe.text_frame(payload)
    written = transport.writeSomeData(frame)
    if not isinstance(written, int):  # an error object: the connection is going; Twisted reports it
        return
    if written < len(frame):
        transport.write(frame[written:])  # type: ignore[no-untyped-call]  # Twisted's is not annotated


def hook_connection(
    factory: Any,
    started: Callable[[], None],
    failed: Callable[[Any], None],
    lost: Callable[[Any], None],
) -> None:
    """Call ``started()`` when a connection attempt starts, ``failed(reason)`` when one is refused or
    unreachable (no close event follows), ``lost(reason)`` when an open one (or its TLS handshake)
    ends; each before the factory's own handling (its reconnect)."""
    original_started = factory.startedConnecting
    original_failed = factory.clientConnectionFailed
    original_lost = factory.clientConnectionLost

    def on_started(connector: Any) -> None:
        started()
        original_started(connector)

    def on_failed(connector: Any, reason: Any) -> None:
        failed(reason)
        original_failed(connector, reason)

    def on_lost(connector: Any, reason: Any) -> None:
        lost(reason)
        original_lost(connector, reason)

    factory.startedConnecting = on_started
    factory.clientConnectionFailed = on_failed
    factory.clientConnectionLost = on_lost


def retry_slowly(factory: Any, seconds: float) -> None:
    """The factory's next attempts ``seconds`` apart (a token refused will be refused again)."""
    factory.delay = max(factory.delay, seconds / factory.factor)
    factory.maxDelay = seconds


def retry_fast(factory: Any, max_delay: float) -> None:
    """Back to attempts at most ``max_delay`` apart (a token was accepted)."""
    factory.maxDelay = max_delay


def handle_op(proto: Any, op: str, handler: Callable[[Any], None]) -> None:
    """Frames of ``op`` (one roslibpy has no handler for, such as "status") go to ``handler``: roslibpy's
    protocol's ``_message_handlers``."""
    proto._message_handlers[op] = handler


def open_protocol(factory: Any) -> Any:
    """The protocol of roslibpy's factory's open connection, or None."""
    return factory._proto
