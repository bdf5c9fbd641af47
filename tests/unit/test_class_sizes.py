"""Issue 48's bounds on the size of the product's classes, kept: no class over 400 lines or 30 methods,
and the app itself (``ArbiterApp``) at most 250 lines. A class that outgrows them is split by its jobs
(as RobotSession, ControlLoop and the rosbridge endpoint were), not given a bigger bound."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("arbiter_core", "arbiter_backend", "arbiter_tui")
MAX_LINES, MAX_METHODS, APP_LINES = 400, 30, 250


def classes() -> list[tuple[str, int, int]]:
    """(where, lines, methods) of every class in the three packages."""
    out = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.ClassDef):
                    lines = (node.end_lineno or node.lineno) - node.lineno + 1
                    methods = sum(isinstance(b, (ast.FunctionDef, ast.AsyncFunctionDef)) for b in node.body)
                    out.append((f"{path.relative_to(ROOT)}:{node.name}", lines, methods))
    return out


def test_no_class_is_over_400_lines_or_30_methods():
    found = classes()
    assert len(found) > 100  # the walk found the product
    too_big = [c for c in found if c[1] > MAX_LINES or c[2] > MAX_METHODS]
    assert too_big == [], too_big


def test_the_app_stays_small():
    (app,) = [c for c in classes() if c[0].endswith("shell/app.py:ArbiterApp")]
    assert app[1] <= APP_LINES, app
