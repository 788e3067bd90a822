"""Imports at the top of a module (issue 42 item 5): an import inside a function is allowed
only with a comment above it (or on its line) that says why, ``# lazy: +N ms at import
otherwise (library)`` with the cost measured, or the other reason a lazy face has
(docs/architecture.md "Imports")."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("analytic", "mujoco_models", "bullet_models", "compare")


def _function_imports(path: Path):
    """(line number, the import's line, the three lines above it) of every import inside a
    function of ``path``."""
    lines = path.read_text().splitlines()
    for node in ast.walk(ast.parse("\n".join(lines))):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for sub in ast.walk(node):
                if isinstance(sub, (ast.Import, ast.ImportFrom)):
                    n = sub.lineno
                    yield n, lines[n - 1], lines[max(0, n - 4):n - 1]


def _modules():
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            if "tests" not in path.relative_to(ROOT).parts:
                yield path


def test_every_function_level_import_says_why():
    bare = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}" for path in _modules()
            for n, line, above in _function_imports(path)
            if "lazy" not in line and not any("lazy" in a for a in above)]
    assert not bare, "\n".join(bare)


def test_the_check_sees_a_bare_import(tmp_path):
    """The walk finds an uncommented import inside a function (the test can fail)."""
    bad = tmp_path / "bad.py"
    bad.write_text("def f():\n    import json\n    return json\n")
    assert [n for n, line, above in _function_imports(bad)] == [2]
