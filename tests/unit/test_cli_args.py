"""Both command lines, in process: every bad value is one line on stderr and exit status 2, before
anything starts; ``--help`` names every flag. (One case per command also runs the real entry point
as a subprocess, in tests/integration.)"""

import pytest

from arbiter_backend import cli as backend_cli
from arbiter_tui import cli as tui_cli


def run_main(main, argv, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize(
    "bad",
    [
        ["--bridge-port", "99999"],
        ["--cmd-timeout", "-1"],
        ["--max-records", "x"],
        ["--cmd-timeout", "nan"],
        ["--max-command-age", "-5"],
        ["--max-linear-accel", "0"],
        ["--max-angular", "inf"],
        ["--measured-type", "pose"],
        ["--ros-args", "-p", "x:=1"],
        ["--unknown-flag"],
    ],
)
def test_backend_bad_values_are_one_line_errors(bad, capsys):
    code, _, err = run_main(backend_cli.main, bad, capsys)
    assert code == 2, bad
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("arbiter-backend: "), (bad, err)


def test_backend_help_mentions_every_flag(capsys):
    code, out, _ = run_main(backend_cli.main, ["--help"], capsys)
    assert code == 0
    for flag in (
        "--host",
        "--bridge-port",
        "--api-port",
        "--deploy-mode",
        "--no-sim",
        "--no-bridge",
        "--max-records",
        "--cmd-timeout",
        "--max-command-age",
        "--max-linear-accel",
        "--max-angular-accel",
        "--allow-remote",
        "--token-file",
        "--log-file",
    ):
        assert flag in out, flag


@pytest.mark.parametrize(
    "args",
    [
        ["--speed", "-1"],
        ["--repeat-rate", "nan"],
        ["--max-points", "0"],
        ["--bridge-port", "70000"],
        ["--export-dir", "/definitely/missing"],
        ["--connect", "--rosbridge", "http://x"],
        ["--connect", "--token-file", "/definitely/missing"],
        ["--offset-warn-ms", "inf"],
        ["--key-timeout", "0"],
        ["--collection-rate", "1e999"],
        ["--transport", "carrier-pigeon"],
        ["--connect", "--sim"],
        ["--bogus"],
        ["stats"],
        ["stats", "a.csv", "b.csv"],
    ],
)
def test_console_bad_values_are_one_line_errors(args, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run_main(tui_cli.main, args, capsys)
    assert code == 2, args
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("arbiter-tui"), err


@pytest.mark.parametrize(
    ("main", "prog"), [(backend_cli.main, "arbiter-backend"), (tui_cli.main, "arbiter-tui")]
)
def test_version_comes_from_the_package_metadata(main, prog, capsys):
    from importlib.metadata import version

    code, out, _ = run_main(main, ["--version"], capsys)
    assert code == 0 and out.strip() == f"{prog} {version('arbiter-tui')}"


def test_help_names_the_log_file_and_the_config_file(capsys):
    code, out, _ = run_main(tui_cli.main, ["--help"], capsys)
    assert code == 0
    flat = " ".join(out.split())
    assert "arbiter-tui-<pid>.log" in flat and "config.toml" in flat and "--print-config" in flat
