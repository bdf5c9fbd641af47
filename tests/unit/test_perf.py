"""The console's patches of Textual and textual-hires-canvas (arbiter_tui/shell/perf/) are installed
explicitly at start-up and only on the releases they were checked against; on any other release these
tests FAIL (they never skip): an upgrade shows up as a red test that names the patch and the release,
never as a patch and its test silently gone together. The releases are pinned in pyproject.toml."""

from arbiter_tui.shell import perf
from arbiter_tui.shell.perf import canvas_rows, strips, theme


def test_every_patch_knows_the_releases_installed_here():
    releases = perf.releases()
    assert releases["textual"] in strips.CHECKED, f"strips: Textual {releases['textual']} not checked"
    assert releases["textual"] in theme.CHECKED, f"theme: Textual {releases['textual']} not checked"
    assert releases["textual-hires-canvas"] in canvas_rows.CHECKED, (
        f"canvas_rows: textual-hires-canvas {releases['textual-hires-canvas']} not checked")  # fmt: skip
    assert perf.install() == {"strips": True, "canvas_rows": True, "theme": True}


def test_a_release_the_patch_does_not_know_is_left_alone(monkeypatch):
    """What happens on an upgrade before the patch is checked again: Textual's own code runs."""
    import textual
    from textual.strip import Strip

    monkeypatch.setattr(textual, "__version__", "99.0.0")
    before = (Strip.divide, Strip.crop_extend)
    assert strips.install() is False and (Strip.divide, Strip.crop_extend) == before
    assert theme.checked() is False


def test_importing_the_console_installs_no_patch():
    """Only start-up (make_app) installs them: importing the shell patches nothing."""
    import subprocess
    import sys

    probe = (
        "from textual.strip import Strip; d = Strip.divide; import arbiter_tui.shell.app; "
        "print(Strip.divide is d)"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60)
    assert out.stdout.strip() == "True", out.stderr


def test_the_theme_lookup_reads_no_package_metadata(monkeypatch):
    """``textual.__version__`` reads package metadata on every access; the lookup runs per rendered line,
    so it must decide once, at install (a per-line check doubled the console's CPU with a key held)."""
    import importlib.metadata

    import textual
    from textual.app import App

    if "__version__" in vars(textual):  # left there by a monkeypatch's undo in an earlier test
        monkeypatch.delitem(vars(textual), "__version__")

    class Themed(theme.RegistryTheme, App[None]):
        pass

    assert perf.install()["theme"] is True
    app = Themed()
    assert app.current_theme.name == app.theme
    reads: list[str] = []
    real = importlib.metadata.version
    monkeypatch.setattr(importlib.metadata, "version", lambda name: reads.append(name) or real(name))
    for _ in range(100):
        assert app.current_theme is not None
    assert reads == []
