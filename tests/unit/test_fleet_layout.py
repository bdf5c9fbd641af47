"""The fleet adds no dependency to the single-robot console: Zenoh is imported by the fleet's session modules
alone, and nothing on the console's or the plain backend's path loads the fleet (import-linter contracts in
pyproject.toml, and at run time with Zenoh blocked)."""


from .test_layout import copy_packages, lint_imports, run_blocked


def test_the_single_console_and_the_plain_backend_import_with_zenoh_blocked():
    modules = ["arbiter_tui.cli", "arbiter_tui.launch", "arbiter_tui.shell.app", "arbiter_backend.cli",
               "arbiter_backend.server", "arbiter_core.fleet", "arbiter_tui.fleet.rows"]  # fmt: skip
    r = run_blocked(modules, {"zenoh"})
    assert r.returncode == 0, r.stderr


def test_the_contracts_catch_zenoh_outside_the_fleet_and_the_fleet_on_the_console_path(tmp_path):
    copy_packages(tmp_path)
    with (tmp_path / "arbiter_tui" / "session" / "robot.py").open("a") as f:
        f.write("\nimport zenoh  # noqa\n")
    with (tmp_path / "arbiter_tui" / "launch.py").open("a") as f:
        f.write("\nimport arbiter_tui.fleet.rows  # noqa\n")
    with (tmp_path / "arbiter_backend" / "server.py").open("a") as f:
        f.write("\nimport arbiter_backend.fleet  # noqa\n")
    r = lint_imports(tmp_path)
    assert r.returncode != 0
    assert "arbiter_tui.session.robot -> zenoh" in r.stdout
    assert "arbiter_tui.launch -> arbiter_tui.fleet.rows" in r.stdout
    assert "arbiter_backend.server -> arbiter_backend.fleet" in r.stdout
