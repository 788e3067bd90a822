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


#: What `treeimpact --help` must not import (issue 52 item 5): the numerics and the engines
#: (numpy alone is 0.1-0.4 s of start-up), and tqdm, which only a drawn progress bar needs.
HEAVY = ("numpy", "scipy", "mujoco", "pybullet", "pandas", "matplotlib", "dask", "tqdm")

_PROBE = """
import atexit, json, sys
def _loaded():
    names = {m.split(".")[0] for m in sys.modules}
    commands = sorted(m for m in sys.modules
                      if m.startswith("treeimpact.compare.interface.commands."))
    print(json.dumps({"heavy": sorted(set(HEAVY) & names), "commands": commands}),
          file=sys.stderr)
atexit.register(_loaded)
from treeimpact.compare.interface.cli import main
sys.exit(main(ARGV))
"""


def _imported_by(argv: list) -> dict:
    """The heavy modules and the command modules loaded by ``treeimpact ARGV`` in a fresh
    interpreter (read at its exit), after checking it printed its usage with exit 0."""
    import json
    import subprocess
    import sys

    code = _PROBE.replace("HEAVY", repr(HEAVY)).replace("ARGV", repr(argv))
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)  # a hang guard, not a speed check
    assert proc.returncode == 0 and proc.stdout.startswith("usage: treeimpact"), proc.stderr
    return json.loads(proc.stderr.strip().splitlines()[-1])


def test_treeimpact_help_imports_no_numerics_and_no_command():
    """`treeimpact --help` lists the commands from compare.interface.commands.HELP: no
    command's module is imported, so none of the numerics or engines behind them (a
    behaviour, not a time: benchmarks/bench_help.py measures what it costs)."""
    assert _imported_by(["--help"]) == {"heavy": [], "commands": []}


def test_a_commands_help_imports_that_command_alone():
    """The control (the probe sees an import): `treeimpact simulate --help` builds the
    simulate parser only, whose backends' options bring numpy; no other command loads."""
    seen = _imported_by(["simulate", "--help"])
    assert "numpy" in seen["heavy"]
    assert seen["commands"] == ["treeimpact.compare.interface.commands._common",
                                "treeimpact.compare.interface.commands.simulate"]


def test_every_command_module_is_the_one_its_name_looks_up():
    """compare.interface.commands.HELP names each command once, and COMMANDS[name] is the
    module whose NAME it is, with the parser's two functions."""
    from treeimpact.compare.interface.commands import COMMANDS, HELP

    assert list(COMMANDS) == list(HELP)
    for name in HELP:
        module = COMMANDS[name]
        assert module.NAME == name and callable(module.add_arguments) and callable(module.run)
    folder = ROOT / "compare" / "interface" / "commands"
    names = {p.stem for p in folder.glob("*.py")} - {"__init__"}
    assert {n for n in names if not n.startswith("_")} == set(HELP)  # no command left out
