"""One set of exit codes (compare/runs/exits.py's ExitCode): the values docs/cli.md documents, read
by every place that returns or checks one; no bare 0, 2, 3 or 130 where a command ends or a
child's exit code is read."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from treeimpact.compare.runs.exits import ExitCode

ROOT = Path(__file__).resolve().parents[1]
#: The modules that return a command's exit code or read a child command's.
INTERFACE = ROOT / "compare" / "interface"
EXIT_MODULES = sorted([INTERFACE / "cli.py", INTERFACE / "process.py",
                       ROOT / "compare" / "report" / "validity" / "study_job.py",
                       *(INTERFACE / "commands").glob("*.py")])
#: The exit codes' values, as literals they would be written with.
VALUES = {int(c) for c in ExitCode}


def test_the_codes_are_the_documented_ones():
    """docs/cli.md's 'Exit codes:' sentence names each code with its meaning."""
    text = " ".join((ROOT / "docs" / "cli.md").read_text().split())
    sentence = re.search(r"Exit codes: (.*?)\. ", text).group(1)
    documented = {int(n): words for n, words in re.findall(r"(\d+) ([a-zA-Z ]+)", sentence)}
    assert documented == {0: "success", 2: "bad input ", 3: "the simulation diverged ",
                          4: "not achieved ", 130: "stopped by Ctrl"}
    assert {c.name: int(c) for c in ExitCode} == {"OK": 0, "BAD_INPUT": 2, "DIVERGED": 3,
                                                 "NOT_ACHIEVED": 4, "INTERRUPTED": 130}


def bare_codes(source: str) -> list[str]:
    """Every ``return N`` and every equality or membership test with N (``==``, ``!=``,
    ``in``, ``not in``), for N an exit code's value written as a bare integer literal (with
    its line), in ``source``."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Return):
            values = [node.value]
        elif isinstance(node, ast.Compare) and any(
                isinstance(op, (ast.Eq, ast.NotEq, ast.In, ast.NotIn)) for op in node.ops):
            values = [node.left, *node.comparators]
            values += [e for v in node.comparators if isinstance(v, (ast.Tuple, ast.List,
                                                                      ast.Set)) for e in v.elts]
        else:
            continue
        out += [f"line {node.lineno}: {ast.unparse(node)}" for v in values
                if isinstance(v, ast.Constant) and type(v.value) is int and v.value in VALUES]
    return out


@pytest.mark.parametrize("path", EXIT_MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_bare_exit_code(path):
    assert bare_codes(path.read_text()) == []


def test_no_130_outside_the_enum():
    """130 means one thing (interrupted): no module of the package spells it but the enum."""
    offenders = []
    for folder in ("compare", "analytic", "treeimpact", "mujoco_models", "bullet_models"):
        for path in (ROOT / folder).rglob("*.py"):
            if "tests" in path.relative_to(ROOT).parts or path.name == "exits.py":
                continue
            offenders += [f"{path.relative_to(ROOT)}:{n.lineno}"
                          for n in ast.walk(ast.parse(path.read_text()))
                          if isinstance(n, ast.Constant) and type(n.value) is int
                          and n.value == 130]
    assert offenders == []


def test_the_check_finds_the_bare_codes_of_before():
    """The check can fail: study_job.py's and a command's code before issue 42."""
    before = ("def result(self):\n    code = self._proc.returncode\n    if code == 0:\n"
              "        return self.out\n    if code == 130:\n        raise KeyboardInterrupt\n"
              "def check(self):\n    return self._proc.poll() not in (None, 0)\n"
              "def run(args):\n    return 0\n")
    assert sorted(bare_codes(before)) == [
        "line 10: return 0", "line 3: code == 0", "line 5: code == 130",
        "line 8: self._proc.poll() not in (None, 0)"]


@pytest.mark.parametrize("error, start", [
    ("NotAchieved", "treeimpact: not achieved: the target"),
    ("OutsideValidity", "treeimpact: outside the model's validity: the target"),
    ("SimulationDiverged", "treeimpact: simulation diverged: the target"),
])
def test_each_way_a_run_falls_short_has_its_code_and_its_words(capsys, error, start):
    """Not achieved and outside the model's validity are exit 4, each in its own words (an
    OutsideValidity is also a SimulationDiverged, yet never worded as diverged); a
    divergence stays exit 3."""
    from treeimpact.analytic import errors
    from treeimpact.compare.interface.process import run_command

    def command(_):
        raise getattr(errors, error)("the target")

    code = run_command(command, None)
    err = capsys.readouterr().err
    assert err == start + "\n"
    assert code == (ExitCode.DIVERGED if error == "SimulationDiverged"
                    else ExitCode.NOT_ACHIEVED)
