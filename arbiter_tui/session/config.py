"""The console's config file: ``$XDG_CONFIG_HOME/arbiter-tui/config.toml`` (or ``--config FILE``).

Keys are the long option names (``odom-topic = "diff_drive_controller/odom"``, ``connect = true``),
plus ``theme``, which the console writes when a theme is chosen in the command palette. Every value is
checked when the file is read: its TOML type (a number, a string, true/false: what the option's
argparse type says, ``arbiter_core.cliargs.takes``), then through the very function the command line
parses the flag with, so one rule decides each value. Command-line flags win. Any problem is one line
naming the file, the line and the key (``config FILE:3: rosbridge: must be a ws:// or wss:// URL
string, got 5``), and exit status 2.

Why these libraries: ``platformdirs`` knows where each platform keeps user config (XDG on Linux,
honouring ``$XDG_CONFIG_HOME``); ``tomllib`` (``tomli`` before Python 3.11) is the standard TOML
reader, and TOML is what Python tools' users already write.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from arbiter_core import cliargs

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

NOT_IN_FILE = {"config", "print_config", "help", "version"}  # command-line only
THEME = "theme"


class ConfigError(ValueError):
    """A config file the console refuses, said in one line."""


def default_path() -> Path:
    from platformdirs import user_config_dir

    return Path(user_config_dir("arbiter-tui", appauthor=False)) / "config.toml"


@dataclass
class Loaded:
    path: Path
    exists: bool
    values: dict[str, Any] = field(default_factory=dict)  # dest -> converted value
    theme: str | None = None


def _line_of(text: str, key: str) -> int | None:
    """The line that sets ``key``: tomllib reports no positions for the values it parsed, so the text is
    scanned for ``key =`` (bare or quoted) at the start of a line."""
    pattern = re.compile(rf"""^\s*["']?{re.escape(key)}["']?\s*=""")
    for number, line in enumerate(text.splitlines(), 1):
        if pattern.match(line):
            return number
    return None


def _options(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    """Long option name (without --) -> its action, for every option a file may set."""
    out = {}
    for action in parser._actions:
        if action.dest in NOT_IN_FILE:
            continue
        for opt in action.option_strings:
            if opt.startswith("--"):
                out[opt[2:]] = action
    return out


def load(path: Path, parser: argparse.ArgumentParser, themes: Sequence[str] = ()) -> Loaded:
    """Read and check ``path`` against ``parser``'s options; a missing file is an empty config."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return Loaded(path, exists=False)
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"config {path}: cannot read it: {exc}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config {path}: {exc}") from None
    options = _options(parser)
    loaded = Loaded(path, exists=True)
    for key, value in data.items():
        line = _line_of(text, key)
        where = f"config {path}:{line}: {key}" if line else f"config {path}: {key}"
        if key == THEME:
            if not isinstance(value, str) or (themes and value not in themes):
                raise ConfigError(f"{where}: not a theme, got {_shown(value)}; one of {', '.join(themes)}")
            loaded.theme = value
            continue
        action = options.get(key)
        if action is None:
            known = ", ".join(sorted([*options, THEME]))
            raise ConfigError(f"{where}: unknown key (the keys are the long option names: {known})")
        loaded.values[action.dest] = _convert(action, value, where)
    return loaded


def _convert(action: argparse.Action, value: Any, where: str) -> Any:
    """A file's value through the command line's own rule for the option: its TOML type first (what the
    flag's argparse type takes), then the type function itself, then the choices."""
    if isinstance(action, (argparse._StoreTrueAction, argparse._StoreFalseAction)):
        if not isinstance(value, bool):
            raise ConfigError(f"{where}: must be true or false, got {_shown(value)}")
        return value if isinstance(action, argparse._StoreTrueAction) else not value
    wanted = cliargs.takes(action.type if callable(action.type) else None)
    if wanted == cliargs.NUMBER:
        fits = isinstance(value, (int, float)) and not isinstance(value, bool)
    elif wanted == cliargs.WHOLE_NUMBER:
        fits = isinstance(value, int) and not isinstance(value, bool)
    else:
        fits = isinstance(value, str)
    if not fits:
        raise ConfigError(f"{where}: must be {wanted}, got {_shown(value)}")
    text = value if isinstance(value, str) else repr(value)
    try:
        converted = action.type(text) if callable(action.type) else text
    except (argparse.ArgumentTypeError, ValueError, TypeError) as exc:
        raise ConfigError(f"{where}: {exc}") from None
    if action.choices is not None and converted not in action.choices:
        raise ConfigError(f"{where}: must be one of {', '.join(map(str, action.choices))}, got {text!r}")
    return converted


def _shown(value: Any) -> str:
    """A value as the file wrote it (TOML), for an error message."""
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "an array"
    return _toml(value)


def given_on_command_line(parser: argparse.ArgumentParser, argv: Sequence[str]) -> set[str]:
    """The dests the command line set (parsed again with every default suppressed)."""
    probe = argparse.ArgumentParser(add_help=False)
    for action in parser._actions:
        if not action.option_strings or action.dest in ("help", "version"):
            continue
        kwargs: dict[str, Any] = {"dest": action.dest, "default": argparse.SUPPRESS}
        if isinstance(action, (argparse._StoreTrueAction, argparse._StoreFalseAction)):
            kwargs["action"] = "store_const"
            kwargs["const"] = True
        probe.add_argument(*action.option_strings, **kwargs)
    ns, _ = probe.parse_known_args(list(argv))
    return set(vars(ns))


def describe(args: argparse.Namespace, parser: argparse.ArgumentParser, loaded: Loaded, cli: set[str]) -> str:
    """``--print-config``: every setting, its value and where it came from."""
    lines = [f"# config file: {loaded.path}{'' if loaded.exists else ' (not there: defaults)'}"]
    for name, action in sorted(_options(parser).items()):
        if name.startswith("no-") and name[3:] in _options(parser):
            continue
        value = getattr(args, action.dest, None)
        source = "default"
        if action.dest in cli:
            source = "command line"
        elif action.dest in loaded.values:
            source = "config"
        if value is None:
            lines.append(f"# {name} is not set    # {source}")
        else:
            lines.append(f"{name} = {_toml(value)}    # {source}")
    theme_source = "config" if loaded.theme else "default"
    lines.append(f"{THEME} = {_toml(loaded.theme or 'textual-dark')}    # {theme_source}")
    return "\n".join(lines)


def _toml(value: Any) -> str:
    """A value as TOML writes it, so that a line of --print-config can be pasted into the file."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    return json.dumps(str(value))


def save_theme(path: Path, theme: str) -> None:
    """Keep the chosen theme in the config file, changing nothing else in it."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        text = ""
    line = f'{THEME} = "{theme}"'
    pattern = re.compile(rf"""^\s*["']?{THEME}["']?\s*=.*$""", re.M)
    if pattern.search(text):
        text = pattern.sub(line, text, count=1)
    else:
        # a bare key must come before any [table]; the console writes none, so the top is safe
        text = f"{line}\n{text}" if text.strip() else f"{line}\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".toml.tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)
