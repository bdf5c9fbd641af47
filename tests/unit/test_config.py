"""The console's config file: values through the command line's own checks, flags win, one-line errors
that name the file, line and key, and the theme kept for next time."""

import pytest

from arbiter_tui import config
from arbiter_tui.launch import build_parser, parse


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
        ("\n\nsped = 1\n", "line 3, key 'sped': unknown key"),
        ('speed = "fast"\n', "line 1, key 'speed': not a number: 'fast'"),
        ("speed = -1\n", "key 'speed': must be a positive finite number"),
        ("connect = 1\n", "key 'connect': must be true or false"),
        ("bridge-port = true\n", "key 'bridge-port': must be a single value"),
        ('transport = "pigeon"\n', "key 'transport': must be one of embedded, ros"),
        ('theme = "pink"\n', "key 'theme': not a theme"),
        ("config = 'x'\n", "key 'config': unknown key"),
    ],
)
def test_every_bad_file_is_one_line_naming_file_line_and_key(tmp_path, capsys, text, words):
    path = write(tmp_path, text)
    assert parse(["--config", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"arbiter-tui: config {path}") and words in err[0], err


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
