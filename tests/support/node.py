"""The field's browser client, npm ``roslib`` (roslibjs), run by node for the tests.

``tests/roslibjs`` pins it (``package.json`` and ``package-lock.json``); ``.ci/run`` installs node and npm
and runs ``npm ci`` there. Where node or npm is missing the tests skip with the reason, unless CI
requires them (``CI=true`` or ``ARBITER_REQUIRE_NODE``, set by ``.ci/run``): then they fail.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import threading
from pathlib import Path
from typing import Any

import pytest

ROSLIBJS = Path(__file__).resolve().parent.parent / "roslibjs"
HELPERS = ROSLIBJS / "helpers.mjs"
NODE_MAJOR_MIN = 20  # roslib 2.x's "engines"
_install_lock = threading.Lock()


def _required() -> bool:
    return os.environ.get("CI", "").lower() == "true" or bool(os.environ.get("ARBITER_REQUIRE_NODE"))


def _unavailable(reason: str) -> None:
    if _required():
        pytest.fail(f"node is required here (CI=true or ARBITER_REQUIRE_NODE) but {reason}", pytrace=False)
    pytest.skip(reason)


def node_major(node: str) -> int:
    out = subprocess.run([node, "--version"], capture_output=True, text=True, timeout=30, check=True).stdout
    return int(out.strip().lstrip("v").split(".")[0])


def roslibjs_ready() -> str:
    """The node binary, with ``tests/roslibjs/node_modules`` installed from the lock (``npm ci`` once);
    skips (or fails where required) with the reason when that cannot be had."""
    node, npm = shutil.which("node"), shutil.which("npm")
    if node is None or npm is None:
        _unavailable("node and npm are not installed (apt-get install nodejs npm; .ci/run does it)")
    assert node is not None and npm is not None
    if (major := node_major(node)) < NODE_MAJOR_MIN:
        _unavailable(f"node {major} is older than roslib 2.x needs ({NODE_MAJOR_MIN})")
    with _install_lock:
        if not (ROSLIBJS / "node_modules" / "roslib" / "package.json").exists():
            done = subprocess.run(
                [npm, "ci", "--no-audit", "--no-fund", "--prefix", str(ROSLIBJS)],
                capture_output=True,
                text=True,
                timeout=600,
            )
            if done.returncode != 0:
                _unavailable(f"npm ci in {ROSLIBJS} failed: {done.stderr.strip()[-500:]}")
    return node


def run_helpers(node: str, url: str, plan: dict[str, Any], timeout: float = 120) -> dict[str, Any]:
    """``helpers.mjs`` against ``url``: its one JSON object (a failure to run is an AssertionError)."""
    done = subprocess.run(
        [node, str(HELPERS), url, json.dumps(plan)], capture_output=True, text=True, timeout=timeout
    )
    lines = done.stdout.strip().splitlines()
    assert lines, f"helpers.mjs printed nothing (exit {done.returncode}): {done.stderr[-2000:]}"
    out = json.loads(lines[-1])
    assert done.returncode == 0 and "fatal" not in out, f"{out.get('fatal')} {done.stderr[-2000:]}"
    return out
