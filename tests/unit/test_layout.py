"""The package layout holds: who imports whom (import-linter contracts in pyproject.toml), checked two ways.

1. ``lint-imports`` over the static import graph, and proof that it catches a violation;
2. at run time: importing any module of ``arbiter_core`` loads none of the I/O or UI frameworks, and
   the whole backend imports with Textual blocked.
"""

import pkgutil
import shutil
import subprocess
import sys
from pathlib import Path

import arbiter_backend
import arbiter_core

ROOT = Path(__file__).resolve().parents[2]
LINT_IMPORTS = Path(sys.executable).with_name("lint-imports")
FRAMEWORKS = {"textual", "rich", "aiohttp", "httpx", "roslibpy", "twisted", "autobahn", "rclpy", "mcap"}


def copy_packages(dest: Path) -> None:
    """The three packages and the contracts, copied for a test to break."""
    for name in ("arbiter_core", "arbiter_backend", "arbiter_tui", "pyproject.toml"):
        src = ROOT / name
        if src.is_dir():
            shutil.copytree(src, dest / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy(src, dest / name)


def lint_imports(cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(LINT_IMPORTS), "--config", str(cwd / "pyproject.toml"), "--no-cache"],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_import_contracts_are_kept():
    r = lint_imports(ROOT)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "12 kept, 0 broken" in r.stdout


def test_import_contracts_catch_a_console_import_of_the_backend_and_textual_in_core(tmp_path):
    copy_packages(tmp_path)
    with (tmp_path / "arbiter_tui" / "shell" / "app.py").open("a") as f:
        f.write("\nimport arbiter_backend.tracker  # noqa\n")
    with (tmp_path / "arbiter_core" / "stats.py").open("a") as f:
        f.write("\nimport textual  # noqa\n")
    r = lint_imports(tmp_path)
    assert r.returncode != 0
    assert "arbiter_tui.shell.app -> arbiter_backend.tracker" in r.stdout
    assert "arbiter_core.stats -> textual" in r.stdout


def test_the_backends_transports_never_import_each_other_and_sit_over_the_shared_config(tmp_path):
    """Issue 54, item 9: the configuration both transports use is neither's module."""
    copy_packages(tmp_path)
    with (tmp_path / "arbiter_backend" / "ros" / "nodes.py").open("a") as f:
        f.write("\nimport arbiter_backend.server  # noqa\n")
    with (tmp_path / "arbiter_backend" / "config.py").open("a") as f:
        f.write("\nimport arbiter_backend.servers  # noqa\n")
    r = lint_imports(tmp_path)
    assert r.returncode != 0
    assert "arbiter_backend.ros.nodes -> arbiter_backend.server" in r.stdout
    assert "arbiter_backend.config -> arbiter_backend.servers" in r.stdout


def modules_of(package) -> list[str]:
    return [
        info.name
        for info in pkgutil.walk_packages(package.__path__, package.__name__ + ".")
        if not info.name.startswith("arbiter_backend.ros")  # the rclpy transport needs the [ros] extra
    ]


def test_every_core_module_imports_without_any_framework():
    mods = modules_of(arbiter_core)
    assert {"arbiter_core.record", "arbiter_core.topics", "arbiter_core.simulator"} <= set(mods)
    code = (
        "import importlib, json, sys\n"
        f"for m in {mods!r}: importlib.import_module(m)\n"
        "print(json.dumps(sorted({n.split('.')[0] for n in sys.modules})))\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    loaded = set(eval(r.stdout))
    assert "arbiter_core" in loaded
    assert not loaded & (FRAMEWORKS | {"arbiter_backend", "arbiter_tui"}), loaded & FRAMEWORKS


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


def run_blocked(modules, blocked):
    code = f"BLOCKED = {set(blocked)!r}\nMODULES = {list(modules)!r}\n" + BLOCKER
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)


def test_whole_backend_imports_without_textual_or_the_console():
    mods = modules_of(arbiter_backend)
    assert "arbiter_backend.tracker" in mods
    r = run_blocked(mods, {"textual", "rich", "arbiter_tui"})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "ok"


def test_pure_console_logic_imports_without_ui_or_network():
    pure = [
        "arbiter_tui.analytics.store",
        "arbiter_tui.analytics.exports",
        "arbiter_core.controllers",
        "arbiter_tui.control.teleop",
        "arbiter_tui.latency.clocksync",
        "arbiter_tui.session.compare",
    ]
    r = run_blocked(pure, {"textual", "rich", "aiohttp", "httpx", "roslibpy", "twisted", "socket"})
    # mcap is only imported lazily by to_mcap, so the pure modules import without it too
    assert r.returncode == 0, r.stderr


def test_the_blocker_really_blocks():
    r = run_blocked(["textual"], {"textual"})
    assert r.returncode != 0 and "blocked import" in r.stderr


def test_the_robots_distribution_is_the_backend_with_the_consoles_own_pins():
    """robot/pyproject.toml (the robot's install) builds arbiter_core and arbiter_backend only, and each
    of its dependencies is one of the console's with the same specifier: a robot never runs a version
    the console's tests did not."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib

    console = tomllib.loads((ROOT / "pyproject.toml").read_text())
    robot = tomllib.loads((ROOT / "robot" / "pyproject.toml").read_text())
    assert robot["tool"]["setuptools"]["packages"]["find"]["include"] == ["arbiter_core*", "arbiter_backend*"]
    backend = console["project"]["scripts"]["arbiter-backend"]
    assert robot["project"]["scripts"] == {"arbiter-backend": backend}
    assert set(robot["project"]["dependencies"]) <= set(console["project"]["dependencies"])
    for extra, needs in robot["project"]["optional-dependencies"].items():
        assert set(needs) <= set(console["project"]["optional-dependencies"][extra]), extra
