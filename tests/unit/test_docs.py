"""The user guide builds, the README's links reach it, and the README stays short.

``mkdocs build --strict`` fails on any warning: a link to a page or a heading that is not there, a page
left out of the nav (``mkdocs.yml``'s ``validation``). The README is not a page of the site, so its links
into ``docs/`` are checked here against the built pages. The pictures in the docs are copies of the
snapshots that make them, so a change of the screens that updates a snapshot updates the docs too."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MKDOCS = Path(sys.executable).with_name("mkdocs")  # the test extra installs it beside this Python


@pytest.fixture(scope="module")
def build(tmp_path_factory) -> tuple[subprocess.CompletedProcess, Path]:
    """Not ``-q``: MkDocs 1.6 counts strict mode's warnings through its log, and ``-q`` silences them
    before they are counted (a broken link then builds with exit 0)."""
    assert MKDOCS.exists(), f"no mkdocs beside {sys.executable}: install the test extra"
    site = tmp_path_factory.mktemp("docs") / "site"
    r = subprocess.run(
        [str(MKDOCS), "build", "--strict", "-f", str(ROOT / "mkdocs.yml"), "-d", str(site)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},  # Material's banner about MkDocs 2
    )
    return r, site


def test_the_readme_is_at_most_200_lines():
    lines = (ROOT / "README.md").read_text().splitlines()
    assert len(lines) <= 200, f"README.md has {len(lines)} lines: move the detail into docs/"


def test_the_guide_builds_strictly(build):
    r, site = build
    warnings = [line for line in (r.stdout + r.stderr).splitlines() if line.startswith("WARNING")]
    assert r.returncode == 0 and not warnings, r.stdout + r.stderr
    assert (site / "index.html").exists()


def test_the_readme_links_reach_their_pages_and_headings(build):
    r, site = build
    assert r.returncode == 0, r.stdout + r.stderr
    checked = 0
    for target in re.findall(r"\]\(([^)\s]+)\)", (ROOT / "README.md").read_text()):
        if target.startswith(("http://", "https://")):
            continue
        path, _, anchor = target.partition("#")
        assert (ROOT / path).exists(), f"README links to {path}, which is not there"
        if path.startswith("docs/") and path.endswith(".md"):
            page = path.removeprefix("docs/").removesuffix(".md")
            html = (site / ("" if page == "index" else page) / "index.html").read_text()
            assert not anchor or f'id="{anchor}"' in html, f"README links to {target}: no such heading"
            checked += 1
    assert checked >= 10


def test_the_pictures_are_the_snapshots_that_make_them():
    """docs/dashboard.svg is test_dashboard[200x60]'s snapshot, docs/analytics_recording.svg
    test_a_recording_on_screen's: after ``pytest tests/tui --snapshot-update`` copy them again."""
    snapshots = ROOT / "tests" / "tui" / "__snapshots__"
    pictures = {
        "dashboard.svg": snapshots / "test_snapshots" / "test_dashboard[200x60].svg",
        "analytics_recording.svg": snapshots / "test_open_recording" / "test_a_recording_on_screen.svg",
    }
    for picture, snapshot in pictures.items():
        copy = ROOT / "docs" / picture
        assert copy.read_bytes() == snapshot.read_bytes(), f"docs/{picture} is not {snapshot.name}: copy it"
