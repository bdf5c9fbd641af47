"""Fixtures of the endpoint tests: an in-process backend without the simulator, and an aiohttp session."""

import aiohttp
import pytest

from arbiter_backend.config import BackendConfig
from arbiter_backend.server import Backend


@pytest.fixture
async def server():
    b = Backend(BackendConfig(bridge_port=0, api_port=0, sim=False))
    await b.start()
    yield b
    await b.stop()


@pytest.fixture
async def session():
    async with aiohttp.ClientSession() as s:
        yield s
