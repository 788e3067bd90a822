"""Functions under 60 lines (the brief's style; issue 42 item 5): every function of the
installed package's source, found by its syntax tree, tests and benchmarks apart."""

from __future__ import annotations

import ast
from pathlib import Path

from treeimpact.compare.runs.backends import ENGINE_REGISTRY

ROOT = Path(__file__).resolve().parents[1]
#: The source folders: the engines' from their registrations.
PACKAGES = ("analytic", *(e.folder for e in ENGINE_REGISTRY.values()), "compare")
#: The most lines a function may span, its signature and docstring included.
MAX_LINES = 60


def long_functions(source: str, name: str = "<source>") -> list[str]:
    """'name:line function (N lines)' for each function of ``source`` over MAX_LINES."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            lines = node.end_lineno - node.lineno + 1
            if lines > MAX_LINES:
                out.append(f"{name}:{node.lineno} {node.name} ({lines} lines)")
    return out


def test_every_function_is_under_60_lines():
    found = [f for pkg in PACKAGES for path in sorted((ROOT / pkg).rglob("*.py"))
             if "tests" not in path.relative_to(ROOT).parts
             for f in long_functions(path.read_text(), str(path.relative_to(ROOT)))]
    assert not found, "\n".join(found)


def test_a_long_function_is_found():
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_LINES))
    assert long_functions(f"def f():\n{body}\n") == [f"<source>:1 f ({MAX_LINES + 1} lines)"]
    assert long_functions("def g():\n    return 1\n") == []
