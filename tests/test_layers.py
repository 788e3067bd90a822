"""The package's shape: one importable top-level name, no import circles, dependencies that
flow one way (analytic <- the engine packages <- compare; inside analytic, from the bottom
floor up), and a public API that resolves and is documented."""

from __future__ import annotations

import ast
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Source folder -> its dotted name once installed.
FOLDERS = {"treeimpact": "treeimpact", "analytic": "treeimpact.analytic",
           "mujoco_models": "treeimpact.mujoco_models",
           "bullet_models": "treeimpact.bullet_models", "compare": "treeimpact.compare"}
#: analytic's floors, bottom first: a module imports only its own floor or lower ones.
ANALYTIC_FLOORS = ("errors", "budget", "results", "model", "records", "impact", "contact",
                   "continuum", "identify", "engine", "paper")


def _modules() -> dict[str, Path]:
    """Every module of the installed package and its file (compare's tests, in
    ``compare/tests/``, are not part of it)."""
    out = {}
    for folder, dotted in FOLDERS.items():
        for path in (ROOT / folder).rglob("*.py"):
            parts = path.relative_to(ROOT / folder).with_suffix("").parts
            if "tests" in parts[:-1]:
                continue
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join((dotted, *parts))] = path
    return out


MODULES = _modules()


def _imported(name: str, path: Path) -> set[str]:
    """The project modules ``name`` imports anywhere in its file (in functions too)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            candidates = [f"{module}.{a.name}" for a in node.names] + [module]
        elif isinstance(node, ast.Import):
            candidates = [a.name for a in node.names]
        else:
            continue
        for c in candidates:  # the module itself, or the closest package that exists
            while c and c not in MODULES:
                c = c.rpartition(".")[0]
            if c and c != name:
                out.add(c)
                break
    return out


GRAPH = {name: _imported(name, path) for name, path in MODULES.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def test_the_import_graph_has_no_circles():
    assert _cycles(GRAPH) == []


def test_the_cycle_finder_finds_a_circle():
    """The check above can fail: a planted circle a -> b -> c -> a is found."""
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def _layer(module: str) -> tuple[str, int]:
    """(top-level part, floor inside analytic) of a module."""
    parts = module.split(".")
    if len(parts) < 2:
        return "treeimpact", 0
    if parts[1] != "analytic":
        return parts[1], 0
    return "analytic", ANALYTIC_FLOORS.index(parts[2]) if len(parts) > 2 else -1


@pytest.mark.parametrize("module", sorted(MODULES))
def test_dependencies_flow_one_way(module):
    """analytic imports neither engine nor compare; an engine package imports analytic only;
    inside analytic no module imports a higher floor (ANALYTIC_FLOORS)."""
    top, floor = _layer(module)
    for dep in GRAPH[module]:
        dep_top, dep_floor = _layer(dep)
        if top == "analytic":
            assert dep_top == "analytic", f"{module} imports {dep}"
            assert dep_floor <= floor, f"{module} (floor {ANALYTIC_FLOORS[floor]}) imports " \
                                       f"{dep} (floor {ANALYTIC_FLOORS[dep_floor]})"
        elif top in ("mujoco_models", "bullet_models"):
            assert dep_top in ("analytic", top), f"{module} imports {dep}"


def test_every_analytic_module_sits_on_a_named_floor():
    for module in MODULES:
        parts = module.split(".")
        if len(parts) > 2 and parts[1] == "analytic":
            assert parts[2] in ANALYTIC_FLOORS, module


def test_no_source_file_imports_a_folder_by_its_bare_name():
    """Code, tests, benchmarks and examples import ``treeimpact.analytic``, never ``analytic``
    (a bare import would be a second copy of the module, or fail once installed)."""
    bare = set(FOLDERS) - {"treeimpact"}
    offenders = []
    for path in ROOT.rglob("*.py"):
        if any(p.startswith(".") for p in path.relative_to(ROOT).parts):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level
                     else [])
            offenders += [f"{path.relative_to(ROOT)}:{node.lineno} {n}" for n in names
                          if n.split(".")[0] in bare]
    assert offenders == []


def test_pyproject_maps_every_package_folder_under_treeimpact():
    """pyproject's explicit package list names exactly the folders that hold an
    __init__.py, each mapped under treeimpact (a missing one would not be installed)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert config["package-dir"] == {dotted: folder for folder, dotted in FOLDERS.items()}
    packages = {name for name, path in MODULES.items() if path.name == "__init__.py"}
    assert set(config["packages"]) == packages
    assert config["package-data"]["treeimpact.analytic.model"] == ["scenarios/*.toml"]


def test_installed_the_project_is_one_top_level_package(tmp_path):
    """From a directory outside the checkout: treeimpact imports, the folders' bare names
    do not (the installed distribution adds one top-level name)."""
    code = ("import importlib, json\n"
            "import treeimpact.analytic.impact.solver, treeimpact.compare.cli\n"
            "out = {}\n"
            "for name in ('analytic', 'compare', 'mujoco_models', 'bullet_models'):\n"
            "    try:\n"
            "        importlib.import_module(name)\n"
            "        out[name] = 'importable'\n"
            "    except ModuleNotFoundError:\n"
            "        out[name] = 'absent'\n"
            "print(json.dumps(out))\n")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert set(__import__("json").loads(proc.stdout).values()) == {"absent"}


def test_the_public_api_resolves_and_is_documented():
    import treeimpact

    doc = (ROOT / "docs" / "api.md").read_text()
    for name in treeimpact.__all__:
        assert getattr(treeimpact, name) is not None
        assert f"`{name}" in doc, f"docs/api.md does not document {name}"
    with pytest.raises(AttributeError):
        treeimpact.no_such_name  # noqa: B018


def test_importing_treeimpact_loads_no_implementation():
    """``import treeimpact`` is cheap: its names load on first use (the CLI's start-up)."""
    code = ("import sys, treeimpact; "
            "print(sorted(m for m in sys.modules if m.startswith('treeimpact')))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60, cwd=ROOT)
    assert proc.stdout.strip() == "['treeimpact']", proc.stdout + proc.stderr
