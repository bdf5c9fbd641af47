"""The console's config file: values through the command line's own checks, flags win, one-line errors
that name the file, line and key, and the theme kept for next time."""

import os

import pytest

from arbiter_tui.launch import build_parser, parse
from arbiter_tui.session import config


def write(tmp_path, text):
    path = tmp_path / "config.toml"
    path.write_text(text)
    return path


def test_values_apply_and_the_command_line_wins(tmp_path, capsys):
    path = write(tmp_path, 'speed = 0.3\nodom-topic = "diff_drive_controller/odom"\nconnect = true\n')
    args, loaded, cli = parse(["--config", str(path), "--speed", "0.2"])
    assert args.speed == 0.2 and "speed" in cli  # the flag wins
    assert args.odom_topic == "diff_drive_controller/odom" and args.connect is True
    assert loaded.values["speed"] == 0.3


def test_a_mode_on_the_command_line_beats_the_files(tmp_path):
    path = write(tmp_path, 'connect = true\nrosbridge = "ws://robot:9090"\n')
    args, _, _ = parse(["--config", str(path), "--sim"])
    assert args.sim and not args.connect and args.rosbridge is None


def test_the_default_file_follows_xdg_config_home(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    assert config.default_path() == tmp_path / "arbiter-tui" / "config.toml"
    (tmp_path / "arbiter-tui").mkdir()
    (tmp_path / "arbiter-tui" / "config.toml").write_text("max-points = 5000\n")
    args, loaded, _ = parse([])
    assert args.max_points == 5000 and loaded.exists


def test_print_config_says_where_each_setting_came_from(tmp_path, capsys):
    path = write(tmp_path, 'namespace = "/robot1"\ntheme = "nord"\n')
    assert parse(["--config", str(path), "--turn", "0.7", "--print-config"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == f"# config file: {path}"
    assert 'namespace = "/robot1"    # config' in out
    assert "turn = 0.7    # command line" in out
    assert "speed = 0.5    # default" in out
    assert 'theme = "nord"    # config' in out
    assert "# ca-file is not set    # default" in out


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("speed = \n", "Invalid value (at line 1, column 9)"),
        ("[table\n", "line 1"),
        ("\n\nsped = 1\n", ":3: sped: unknown key"),
        ('speed = "fast"\n', ':1: speed: must be a number, got "fast"'),
        ("speed = -1\n", "speed: must be a positive finite number"),
        ("connect = 1\n", "connect: must be true or false"),
        ("bridge-port = true\n", "bridge-port: must be a whole number, got true"),
        ('transport = "pigeon"\n', "transport: must be one of embedded, ros"),
        ('theme = "pink"\n', "theme: not a theme"),
        ("config = 'x'\n", "config: unknown key"),
        # issue 31: these passed --print-config and failed later, or said "must be a single value"
        ("# robot\n\nrosbridge = 5\n", ":3: rosbridge: must be a ws:// or wss:// URL string, got 5"),
        ('export-dir = "/nonexistent"\n', ":1: export-dir: no such directory: /nonexistent"),
        ("speed = true\n", ":1: speed: must be a number, got true"),
        ('rosbridge = "http://robot:9090"\n', "rosbridge: URL must start with ws:// or wss://"),
        ('tracker = "ws://robot:8085"\n', "tracker: URL must start with http:// or https://"),
        ('namespace = "robot 1"\n', "namespace: namespace '/robot 1': each part must start"),
        ('odom-topic = "~/odom"\n', "odom-topic: topic '~/odom': a private (~) name"),
        ('ca-file = "/nonexistent/ca.pem"\n', "ca-file: no such file: /nonexistent/ca.pem"),
        ('token-file = "/"\n', "token-file: / is a directory, not a file"),
        ("max-points = 5000.5\n", "max-points: must be a whole number, got 5000.5"),
        ('log-level = "loud"\n', "log-level: must be one of DEBUG, INFO, WARNING, ERROR"),
        ("log-file = 3\n", "log-file: must be a string, got 3"),
        ("speed = [0.3]\n", "speed: must be a number, got an array"),
    ],
)
def test_every_bad_file_is_one_line_naming_file_line_and_key(tmp_path, capsys, text, words):
    path = write(tmp_path, text)
    assert parse(["--config", str(path), "--print-config"]) == 2  # refused when read, before anything
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"arbiter-tui: config {path}") and words in err[0], err


def test_export_dir_in_the_file_must_be_a_directory_this_user_can_write(tmp_path, capsys):
    """The same rule as --export-dir: an existing directory, writable (never created on a typo)."""
    from arbiter_core.cliargs import NOT_WRITABLE

    a_file = tmp_path / "file"
    a_file.write_text("")
    read_only = tmp_path / "ro"
    read_only.mkdir(mode=0o555)
    for target, words in [(a_file, "is a file, not a directory"), (read_only, NOT_WRITABLE)]:
        if target == read_only and os.access(read_only, os.W_OK):  # root: a directory that takes no file
            target = "/proc"
        path = write(tmp_path, f'export-dir = "{target}"\n')
        assert parse(["--config", str(path)]) == 2
        (line,) = capsys.readouterr().err.strip().splitlines()
        assert line.startswith(f"arbiter-tui: config {path}:1: export-dir: ") and words in line, line
    path = write(tmp_path, f'export-dir = "{tmp_path}"\n')
    args, _, _ = parse(["--config", str(path)])
    assert args.export_dir == tmp_path


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("rosbridge", "http://robot:9090"),
        ("export-dir", "/nonexistent"),
        ("namespace", "robot 1"),
        ("speed", "-1"),
        ("bridge-port", "70000"),
        ("ca-file", "/nonexistent/ca.pem"),
    ],
)
def test_the_file_and_the_flag_say_the_same_for_the_same_value(tmp_path, capsys, monkeypatch, key, value):
    """One rule decides each value: the command line's message for --KEY VALUE is the file's."""
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "none"))  # no user config file in the way
    path = write(tmp_path, f"{key} = {value if key in ('speed', 'bridge-port') else repr(value)}\n")
    assert parse(["--config", str(path)]) == 2
    from_file = capsys.readouterr().err.strip().split(f":1: {key}: ", 1)[1]
    with pytest.raises(SystemExit) as exit_:
        parse([f"--{key}", value])
    assert exit_.value.code == 2
    from_flag = capsys.readouterr().err.strip()
    assert from_flag == f"arbiter-tui: argument --{key}: {from_file} (see --help)"


def test_an_explicit_file_must_exist(tmp_path, capsys):
    assert parse(["--config", str(tmp_path / "nope.toml")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_the_theme_is_saved_without_touching_the_rest(tmp_path):
    path = write(tmp_path, "# mine\nspeed = 0.3\n")
    config.save_theme(path, "nord")
    config.save_theme(path, "dracula")
    assert path.read_text() == 'theme = "dracula"\n# mine\nspeed = 0.3\n'
    loaded = config.load(path, build_parser(), ["nord", "dracula"])
    assert loaded.theme == "dracula" and loaded.values == {"speed": 0.3}
    fresh = tmp_path / "new" / "config.toml"
    config.save_theme(fresh, "nord")
    assert fresh.read_text() == 'theme = "nord"\n'
