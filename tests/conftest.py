"""Fixtures shared by every layer; helpers live in ``tests/support`` and are imported from there."""

from pathlib import Path

import pytest

from .support.backend import start_backend


@pytest.fixture
def backend():
    b = start_backend()
    yield b
    b.stop()


LAYERS = ("unit", "tui", "integration")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark each test with its layer, the folder it lives in, so ``-m unit`` etc. select a layer."""
    for item in items:
        layer = Path(str(item.path)).parent.name
        if layer in LAYERS:
            item.add_marker(getattr(pytest.mark, layer))
