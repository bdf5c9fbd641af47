"""The backend finds what a bus or a backend can do by isinstance on protocols (arbiter_backend/bus.py,
arbiter_backend/fleet.py), as the console does (arbiter_tui/link/base.py), never by probing a name with
getattr/hasattr: a rename then fails the type check (ros/bus.py and fleet.py state what each transport
has, for mypy: tests/unit/test_types.py) instead of silently turning a feature off (issue 54, item 8)."""

import ast
from pathlib import Path

from arbiter_backend.bridge.encoding import Encoder
from arbiter_backend.bus import ConvertingBus, GraphBus, TopicBus
from arbiter_backend.config import BackendConfig
from arbiter_backend.fleet import RunsAutonomy, RunsNodes, sources_of
from arbiter_backend.server import Backend

BACKEND = Path(__file__).resolve().parents[2] / "arbiter_backend"
PARTS = {"bus", "backend", "graph", "endpoint"}  # what a capability is asked of


def probes(path: Path) -> list[str]:
    """getattr/hasattr calls on a bus, a backend, its graph or its endpoint, as file:line."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.args):
            continue
        target = ast.unparse(node.args[0])
        if node.func.id in ("getattr", "hasattr") and any(part in target for part in PARTS):
            found.append(f"{path.relative_to(BACKEND)}:{node.lineno} {ast.unparse(node)}")
    return found


def test_no_capability_is_probed_by_name():
    found = [p for path in sorted(BACKEND.rglob("*.py")) for p in probes(path)]
    assert found == []


def test_the_embedded_transport_has_its_capabilities_and_not_the_ros_ones():
    bus = TopicBus()
    assert not isinstance(bus, GraphBus) and not isinstance(bus, ConvertingBus)
    assert Encoder(bus).serialises is False  # cbor-raw refused on it (test_bridge_cbor)
    backend = Backend(BackendConfig(autonomy=True))
    assert isinstance(backend, RunsAutonomy) and not isinstance(backend, RunsNodes)
    src = sources_of(backend)
    assert src.autonomy is backend.autonomy is not None and src.watch is backend.topics.watch
    assert "autonomy" in src.mode
