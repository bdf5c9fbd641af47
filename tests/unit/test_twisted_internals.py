"""The rosbridge link's reads of Twisted's internals (arbiter_tui/link/twisted_internals.py) are used only
on the Twisted releases they were checked against; on any other release these tests FAIL (they never
skip): an upgrade shows up as a red test naming the release (issue 54, item 10). Twisted is bounded in
pyproject.toml."""

import ast
from pathlib import Path

import twisted
from twisted.internet import tcp

from arbiter_tui.link import twisted_internals as ti

LINK = Path(__file__).resolve().parents[2] / "arbiter_tui" / "link"


class Socket(tcp.Client):
    """Twisted's own TCP client transport, not connected: what the fast path writes into."""

    def __init__(self) -> None:  # no socket: only the buffers the fast path reads
        self.TLS = False
        self.dataBuffer = b""
        self._tempDataBuffer = []
        self.written: list[bytes] = []

    def writeSomeData(self, data):
        self.written.append(bytes(data))
        return len(data)


class Proto:
    STATE_OPEN = 3
    state = STATE_OPEN

    def __init__(self) -> None:
        self.transport = Socket()
        self.sent: list[bytes] = []

    def sendMessage(self, payload, isBinary):
        self.sent.append(payload)


def test_the_twisted_release_installed_here_was_checked(monkeypatch):
    assert ti.checked(), f"Twisted {twisted.__version__} was not checked (checked: {ti.CHECKED})"
    monkeypatch.setattr(ti, "_installed", None)
    assert ti.install() is True
    proto = Proto()
    ti.write_now(proto, b'{"op":"publish"}')
    assert proto.sent == [] and len(proto.transport.written) == 1  # straight into the socket


def test_a_release_not_checked_takes_the_public_path(monkeypatch):
    monkeypatch.setattr(twisted, "__version__", "99.1.0")
    monkeypatch.setattr(ti, "_installed", None)
    assert ti.checked() is False and ti.install() is False
    proto = Proto()
    ti.write_now(proto, b'{"op":"publish"}')
    assert proto.sent == [b'{"op":"publish"}'] and proto.transport.written == []
    assert ti.checked("26.10.3") and not ti.checked("26.1.0") and not ti.checked("27.0.0")


def test_no_other_link_module_reaches_inside_twisted_or_roslibpys_factory():
    """Every private attribute of Twisted or of roslibpy's factory is read in twisted_internals alone."""
    private = {"_proto", "_tempDataBuffer", "dataBuffer", "startedConnecting", "clientConnectionFailed",
               "clientConnectionLost", "maxDelay", "_message_handlers"}  # fmt: skip
    for path in sorted(LINK.glob("*.py")):
        if path.name == "twisted_internals.py":
            continue
        names = {n.attr for n in ast.walk(ast.parse(path.read_text())) if isinstance(n, ast.Attribute)}
        assert not names & private, f"{path.name} reaches {sorted(names & private)}"
