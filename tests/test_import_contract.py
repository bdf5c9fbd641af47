"""The backend never imports Textual; pure modules import no I/O-heavy or UI libraries."""

import pkgutil
import subprocess
import sys

import arbiter_backend

PURE = [
    "arbiter_backend.core.stats",
    "arbiter_backend.core.envelope",
    "arbiter_backend.core.record",
    "arbiter_backend.core.kinematics",
    "arbiter_backend.core.control",
    "arbiter_backend.core.analytics",
    "arbiter_backend.core.exports",
]

BLOCKER = """
import sys
class Block:
    def __init__(self, names): self.names = names
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] in self.names:
            raise ImportError('blocked import of ' + name)
        return None
sys.meta_path.insert(0, Block(BLOCKED))
import importlib
for m in MODULES:
    importlib.import_module(m)
print('ok')
"""


def backend_modules():
    names = []
    for info in pkgutil.walk_packages(arbiter_backend.__path__, "arbiter_backend."):
        if info.name.startswith("arbiter_backend.ros"):
            continue  # the rclpy transport needs the [ros] extra
        names.append(info.name)
    return names


def run_blocked(modules, blocked):
    code = f"BLOCKED = {set(blocked)!r}\nMODULES = {list(modules)!r}\n" + BLOCKER
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)


def test_whole_backend_imports_without_textual():
    mods = backend_modules()
    assert "arbiter_backend.core.analytics" in mods
    r = run_blocked(mods, {"textual", "rich"})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "ok"


def test_pure_core_needs_no_network_or_ui_libraries():
    r = run_blocked(PURE, {"textual", "rich", "aiohttp", "httpx", "roslibpy", "twisted", "asyncio", "socket"})
    # mcap is only imported lazily by to_mcap, so the pure modules import without it too
    assert r.returncode == 0, r.stderr


def test_the_blocker_really_blocks():
    r = run_blocked(["textual"], {"textual"})
    assert r.returncode != 0 and "blocked import" in r.stderr
