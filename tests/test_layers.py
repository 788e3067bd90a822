"""The package's shape: one importable top-level name, no import circles (between modules,
or between the units of a package: its modules and subpackages), dependencies that flow one
way (analytic <- the engine packages <- compare; inside analytic and inside compare, from the
bottom floor up; docs/architecture.md), engines reached through their public interface, and
a public API that resolves and is documented."""

from __future__ import annotations

import ast
import re
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
ANALYTIC_FLOORS = ("threads", "errors", "budget", "results", "model", "records", "impact",
                   "contact", "continuum", "identify", "engine", "paper")
#: compare's floors, bottom first (docs/architecture.md): each a set of units (a module or
#: a subpackage of compare); a module imports only its own floor or lower ones, and the
#: units of one floor import each other without a circle.
COMPARE_FLOORS = (
    # 1 what a run is: the backends by name, one run record, verdicts, the rung table, the pool
    ("names", "provenance", "recording", "progress", "pool", "backends", "runs", "verdicts",
     "rungs"),
    # 2 one scenario, one record, one contact: the ladder and the identification
    ("identification", "ladder", "mechanism", "contact_engines", "contact_settings"),
    # 3 the sweep machinery: grid, plan, run, journal, maps
    ("sweep",),
    # 4 the studies built on sweeps: contact scan, small e, sensitivity, identification, speed
    ("studies",),
    # 5 the report: sections rendered from results
    ("report",),
    # 6 the model-validity study (it renders its page with the report's templates)
    ("validity",),
    # 7 the interface: the public API and the command line
    ("api_results", "api", "process", "cli", "commands"),
)
ENGINES = ("mujoco_models", "bullet_models")


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
#: A ``module:function`` reference in a string, resolved by importlib (the backends'
#: registry, the sweeps' analyses): an import as much as an import statement.
_REFERENCE = re.compile(r"(treeimpact(?:\.\w+)+):\w+")


def _closest(name: str, modules) -> str:
    """``name`` if it is a module, else the closest package above it that is ('' if none)."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name


def _imports_of(name: str, package: str, source: str, modules=MODULES) -> set[str]:
    """The project modules the source of module ``name`` (in package ``package``) imports
    anywhere (in functions too): every name of every import, and every ``module:function``
    reference in a string."""
    out = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            # each name is a submodule, or a name in the module (or the closest package)
            found = {_closest(f"{module}.{a.name}", modules) for a in node.names}
        elif isinstance(node, ast.Import):
            found = {_closest(a.name, modules) for a in node.names}
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            found = {_closest(m, modules) for m in _REFERENCE.findall(node.value)}
        else:
            continue
        out |= {m for m in found if m and m != name}
    return out


def _imported(name: str, path: Path) -> set[str]:
    """The project modules ``name`` imports anywhere in its file (:func:`_imports_of`)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    return _imports_of(name, package, path.read_text())


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


def _unit(module: str) -> str:
    """The unit a module belongs to: its top-level package's module or subpackage
    (``treeimpact.compare.sweep`` for treeimpact.compare.sweep.run)."""
    return ".".join(module.split(".")[:3])


def _unit_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """The import graph between units (a package-level circle is a circle here)."""
    units: dict[str, set[str]] = {}
    for module, deps in graph.items():
        units.setdefault(_unit(module), set()).update(
            _unit(d) for d in deps if _unit(d) != _unit(module))
    for deps in list(units.values()):
        for d in deps:
            units.setdefault(d, set())
    return units


def test_no_circle_between_packages():
    """No circle between the units of a package either (sweep/ and report/, a study and
    report/...), function-level imports included: each subpackage is one node."""
    assert _cycles(_unit_graph(GRAPH)) == []


def test_a_circle_between_packages_is_found():
    """Two modules of one subpackage that import a third module each way round form a
    circle at the package level, though not between modules."""
    graph = {"t.c.sweep.study": {"t.c.report.base"}, "t.c.report.base": set(),
             "t.c.report": {"t.c.sweep.run"}, "t.c.sweep.run": set()}
    assert _cycles(graph) == []
    assert _cycles(_unit_graph(graph)) == [["t.c.report", "t.c.sweep"]]


def test_the_import_finder_sees_every_name_and_reference():
    """Every name of a from-import counts (``from treeimpact.analytic import errors,
    paper`` imports both modules), in functions too, and so does a ``module:function``
    string that importlib resolves."""
    modules = {"treeimpact.analytic.errors", "treeimpact.analytic.paper",
               "treeimpact.analytic.results", "treeimpact.compare.x",
               "treeimpact.mujoco_models"}
    source = ("from treeimpact.analytic import errors, paper\n"
              "def f():\n    from treeimpact.analytic.results import METRIC_KEYS\n"
              "RUN = 'treeimpact.mujoco_models:simulate'\n")
    assert _imports_of("treeimpact.compare.x", "treeimpact.compare", source, modules) == {
        "treeimpact.analytic.errors", "treeimpact.analytic.paper",
        "treeimpact.analytic.results", "treeimpact.mujoco_models"}


def _floor(floors: tuple, unit: str) -> int:
    """The floor (0 = bottom) of a unit named in ``floors`` (a name or a tuple of names per
    floor); -1 for the package itself."""
    for i, names in enumerate(floors):
        if unit in ((names,) if isinstance(names, str) else names):
            return i
    return -1


def _layer(module: str) -> tuple[str, int]:
    """(top-level part, floor inside analytic or compare) of a module."""
    parts = module.split(".")
    if len(parts) < 2:
        return "treeimpact", 0
    floors = {"analytic": ANALYTIC_FLOORS, "compare": COMPARE_FLOORS}.get(parts[1])
    if floors is None:
        return parts[1], 0
    return parts[1], _floor(floors, parts[2]) if len(parts) > 2 else -1


def _floor_name(top: str, floor: int) -> str:
    """The units of a floor, for a message ('the package' below the bottom floor)."""
    if floor < 0:
        return "the package"
    names = {"analytic": ANALYTIC_FLOORS, "compare": COMPARE_FLOORS}[top][floor]
    return names if isinstance(names, str) else "/".join(names)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_dependencies_flow_one_way(module):
    """analytic imports neither engine nor compare; an engine package imports analytic only;
    inside analytic and inside compare no module imports a higher floor (ANALYTIC_FLOORS,
    COMPARE_FLOORS)."""
    top, floor = _layer(module)
    for dep in GRAPH[module]:
        dep_top, dep_floor = _layer(dep)
        if top == "analytic":
            assert dep_top == "analytic", f"{module} imports {dep}"
        elif top in ENGINES:
            assert dep_top in ("analytic", top), f"{module} imports {dep}"
        if top in ("analytic", "compare") and dep_top == top:
            assert dep_floor <= floor, (
                f"{module} (floor {floor + 1}, {_floor_name(top, floor)}) imports {dep} "
                f"(floor {dep_floor + 1}, {_floor_name(top, dep_floor)})")


@pytest.mark.parametrize("top", ["analytic", "compare"])
def test_every_module_sits_on_a_named_floor(top):
    for module in MODULES:
        parts = module.split(".")
        if len(parts) > 2 and parts[1] == top:
            assert _layer(module)[1] >= 0, f"{module}: name its unit in the floors above"


def test_engines_are_reached_through_their_public_interface():
    """Outside an engine package nothing imports its private modules (``_runner``,
    ``_contact``, ...): what compare needs, the package's __init__ exports."""
    offenders = [f"{module} imports {dep}" for module, deps in GRAPH.items() for dep in deps
                 if dep.split(".")[1] in ENGINES and dep.split(".")[1] != module.split(".")[1]
                 and any(p.startswith("_") for p in dep.split(".")[2:])]
    assert offenders == []


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


#: The package data the wheel carries: source folder -> patterns of files in it.
PACKAGE_DATA = {"analytic/model": ["scenarios/*.toml"], "compare": ["tolerances.toml"],
                "compare/report": ["templates/*.j2"], "mujoco_models": ["models/*.xml"],
                "bullet_models": ["models/*.urdf"]}


@pytest.fixture(scope="module")
def wheel_files(tmp_path_factory) -> set[str]:
    """The files of the wheel built from a copy of the checkout (offline: no build isolation,
    no index; the checkout itself is left without a build/ folder)."""
    import shutil
    import zipfile

    src, dist = tmp_path_factory.mktemp("src"), tmp_path_factory.mktemp("dist")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for folder in FOLDERS:
        shutil.copytree(ROOT / folder, src / folder,
                        ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-index",
                           "--no-build-isolation", "-q", "-w", str(dist), str(src)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    (wheel,) = dist.glob("treeimpact-*.whl")
    return set(zipfile.ZipFile(wheel).namelist())


def test_the_wheel_holds_the_library_and_no_tests_or_tooling(wheel_files):
    """No test module, conftest or tests folder and no docs tooling is installed."""
    shipped = [f for f in wheel_files if f.startswith("treeimpact/")]
    assert shipped
    names = [Path(f).name for f in shipped]
    assert not [n for n in names if n.startswith("test_") or n == "conftest.py"]
    assert not [f for f in shipped if "/tests/" in f or "docnumbers" in f
                or f.endswith("compare/docs.py")]


def test_the_wheel_holds_every_module_and_its_data(wheel_files):
    """Every module of the package (tests/test_layers.py's MODULES) and every file of the
    package data (scenarios, tolerances.toml, the report's templates, the engines' models)."""
    def installed(path: Path) -> str:
        parts = path.relative_to(ROOT).parts  # a folder is its subpackage of treeimpact
        return "/".join(parts if parts[0] == "treeimpact" else ("treeimpact", *parts))

    modules = sorted(installed(p) for p in MODULES.values())
    assert len(modules) > 100 and [m for m in modules if m not in wheel_files] == []
    data = [installed(p) for folder, patterns in PACKAGE_DATA.items() for pattern in patterns
            for p in sorted((ROOT / folder).glob(pattern))]
    assert len(data) > 10 and [f for f in data if f not in wheel_files] == []
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert {f"treeimpact.{k.replace('/', '.')}": v for k, v in PACKAGE_DATA.items()} == \
        config["package-data"]


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
