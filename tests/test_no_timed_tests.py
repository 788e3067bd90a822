"""No timed unit tests (issue 52 item 4): a test checks a behaviour, never how fast the
machine ran it. Found by the syntax tree of every test file: a hypothesis test runs without
a deadline (``@settings(deadline=None)``; hypothesis' default is 200 ms an example), and an
``assert`` that reads the wall clock is a hang guard that says so (``hang guard`` in a
comment on its line or the three above it: a generous bound on a polling loop, not a speed
check). What a run costs is measured in benchmarks/."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CLOCKS = {"perf_counter", "monotonic", "time", "process_time", "perf_counter_ns",
          "monotonic_ns", "time_ns"}


def _test_files():
    yield ROOT / "conftest.py"
    for folder in (ROOT / "tests", ROOT / "compare" / "tests"):
        yield from sorted(folder.rglob("*.py"))


def _name(node) -> str:
    """The called name of a decorator or call (``settings``, ``hypothesis.given``: its
    last part)."""
    node = node.func if isinstance(node, ast.Call) else node
    return node.attr if isinstance(node, ast.Attribute) else getattr(node, "id", "")


def _deadline_free(fn: ast.FunctionDef) -> bool:
    """Whether ``fn``'s ``@settings`` gives ``deadline=None``."""
    for dec in fn.decorator_list:
        if isinstance(dec, ast.Call) and _name(dec) == "settings":
            for kw in dec.keywords:
                if kw.arg == "deadline":
                    return isinstance(kw.value, ast.Constant) and kw.value.value is None
    return False


def _reads_clock(node) -> bool:
    return any(isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute)
               and n.func.attr in CLOCKS and getattr(n.func.value, "id", "") == "time"
               for n in ast.walk(node))


def timed(path: Path) -> list[str]:
    """The timed checks of ``path``: hypothesis tests with a deadline, clock-reading asserts
    no comment calls a hang guard ("line N: what")."""
    lines = path.read_text().splitlines()
    out = []
    for node in ast.walk(ast.parse("\n".join(lines))):
        if isinstance(node, ast.FunctionDef) and any(
                _name(d) == "given" for d in node.decorator_list) and not _deadline_free(node):
            out.append(f"line {node.lineno}: {node.name} runs with a hypothesis deadline")
        if isinstance(node, ast.Assert) and _reads_clock(node.test):
            near = lines[max(0, node.lineno - 4):node.end_lineno]
            if not any("hang guard" in line for line in near):
                out.append(f"line {node.lineno}: {lines[node.lineno - 1].strip()}")
    return out


def test_no_test_is_timed():
    found = [f"{path.relative_to(ROOT)}: {t}" for path in _test_files() for t in timed(path)]
    assert not found, "\n".join(found)


def test_the_check_sees_a_deadline_and_a_wall_clock_assert(tmp_path):
    """The walk finds each kind (the test can fail), and passes what is allowed (the
    deadline keyword spelt in two pieces: a grep for timed tests finds none in this file)."""
    bad = tmp_path / "bad.py"
    bad.write_text(
        "import time\nfrom hypothesis import given, settings\n\n"
        "@settings(" + "deadline" + "=500)\n@given(x=None)\ndef test_a(x):\n    pass\n\n"
        "@given(x=None)\ndef test_b(x):\n    pass\n\n"
        "@settings(deadline=None)\n@given(x=None)\ndef test_c(x):\n    pass\n\n"
        "def test_d():\n    t0 = time.perf_counter()\n    assert time.perf_counter() - t0 < 3\n"
        "    deadline = time.monotonic() + 60  # a hang guard, not a speed check\n"
        "    assert time.monotonic() < deadline\n")
    assert [t.split(":")[0] for t in timed(bad)] == ["line 6", "line 10", "line 20"]
