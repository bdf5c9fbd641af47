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
        ["--robot-name", "lab 01"],  # not a name the fleet could announce
        ["--label", "x"],  # observe mode's flags without --observe: said, not silently ignored
        ["--sim", "--plan-topic", "/plan2", "--cmd-stamped"],
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


def test_help_names_every_subcommand(capsys):
    code, out, _ = run_main(tui_cli.main, ["--help"], capsys)
    assert code == 0
    flat = " ".join(out.split())
    for name in ("compare", "stats", "topics", "autonomy", "fleet"):
        assert f"'arbiter-tui {name} " in flat, name
        assert tui_cli._command(name) is not None


def test_observe_flags_without_observe_say_which(capsys):
    code, _, err = run_main(tui_cli.main, ["--label", "nav2_rpp", "--goal-topic", "/g"], capsys)
    assert code == 2 and err == "arbiter-tui: --label, --goal-topic: only with --observe (observe mode)\n"


@pytest.mark.parametrize(
    ("argv", "prog"),
    [
        (["--export-dir", "/proc", "--print-config"], "arbiter-tui"),
        (["compare", "--mission", "corner", "--algorithms", "stanley", "--export-dir", "/proc"],
         "arbiter-tui compare"),
    ],
)  # fmt: skip
def test_an_export_dir_that_takes_no_files_is_not_writable_even_for_root(argv, prog, capsys, tmp_path):
    """Issue 46: root passes the permission check of /proc, and the export then failed with "No such
    file or directory". Every command with --export-dir tries a file there first, and says what is wrong."""
    from arbiter_core.cliargs import NOT_WRITABLE

    code, out, err = run_main(tui_cli.main, argv, capsys)
    assert (code, out) == (2, "")
    assert err.splitlines() == [f"{prog}: argument --export-dir: /proc: {NOT_WRITABLE} (see --help)"]


def test_a_writable_export_dir_is_left_as_it_was(tmp_path):
    from arbiter_core.cliargs import writable_dir

    (tmp_path / "kept").write_text("x")
    assert writable_dir(str(tmp_path)) == tmp_path
    assert [p.name for p in tmp_path.iterdir()] == ["kept"]  # the trial file is gone
