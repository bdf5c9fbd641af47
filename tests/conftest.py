"""Fixtures shared by every layer; helpers live in ``tests/support`` and are imported from there."""

from pathlib import Path

import pytest

from .support.backend import start_backend


@pytest.fixture(autouse=True)
def _own_cache_dir(tmp_path_factory, monkeypatch):
    """Every test its own user cache and data directories (XDG): the analytics sweep keeps its curves in
    the one, the console its journal in the other, and a test must neither read a developer's nor leave
    its own."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.mktemp("cache")))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path_factory.mktemp("data")))


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
