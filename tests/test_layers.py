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

from treeimpact.compare.runs.backends import ENGINE_REGISTRY

ROOT = Path(__file__).resolve().parents[1]
#: The engines' source folders, from their registrations (compare.runs.backends.ENGINE_REGISTRY).
ENGINES = tuple(e.folder for e in ENGINE_REGISTRY.values())
#: Source folder -> its dotted name once installed.
FOLDERS = {"treeimpact": "treeimpact", "analytic": "treeimpact.analytic",
           **{folder: f"treeimpact.{folder}" for folder in ENGINES},
           "compare": "treeimpact.compare"}
#: analytic's floors, bottom first: a module imports only its own floor or lower ones.
ANALYTIC_FLOORS = ("threads", "errors", "budget", "metrics", "results", "model", "records",
                   "impact", "contact", "continuum", "identify", "engine", "paper",
                   "references")
#: compare's floors, bottom first (docs/architecture.md): each a set of units (a module or
#: a subpackage of compare); a module imports only its own floor or lower ones, and the
#: units of one floor import each other without a circle.
COMPARE_FLOORS = (
    # 1 runs/: what a run is: backends, one Run record, tolerances and verdicts, rungs, the pool
    ("runs",),
    # 2 tree/: one tree: its ladder judged, its record fit, a user's tree, the family of trees
    ("tree",),
    # 3 studies/: the sweep machinery (studies/sweep/) and the studies built on sweeps
    ("studies",),
    # 4 report/: the report's sections, and the validity study's pages (report/validity/)
    ("report",),
    # 5 interface/: the public API, one module per command, the parser, the process policy
    ("interface",),
)


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
#: A project module named in a string: ``module:function`` (resolved by importlib: the
#: backends' registry, the sweeps' analyses), a dotted module name (a forkserver's preload
#: list) or a ``-m`` command line (a child process): a dependency as much as an import.
_NAMED = re.compile(r"(?:(-m)\s+)?\b(treeimpact(?:\.\w+)+)(?::(\w+))?")


def _closest(name: str, modules) -> str:
    """``name`` if it is a module, else the closest package above it that is ('' if none)."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name


def _docstrings(tree) -> set[int]:
    """The ids of the docstring nodes of a module, its classes and functions (prose: a name
    there is documentation, not a use)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) \
                and node.body and isinstance(node.body[0], ast.Expr) \
                and isinstance(node.body[0].value, ast.Constant):
            out.add(id(node.body[0].value))
    return out


def _named_in_strings(source: str) -> list[tuple[str, str | None, bool]]:
    """Every project module a string of ``source`` names outside docstrings: (dotted name,
    the function after its colon or None, whether a ``-m`` launches it), whether the ``-m``
    is in the same string or the element before it in a list or tuple."""
    tree = ast.parse(source)
    docs, launched = _docstrings(tree), set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.List, ast.Tuple)):
            launched |= {id(b) for a, b in zip(node.elts, node.elts[1:])
                         if isinstance(a, ast.Constant) and a.value == "-m"}
    return [(m, function or None, bool(dash) or id(node) in launched)
            for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str)
            and id(node) not in docs
            for dash, m, function in _NAMED.findall(node.value)]


def _references_of(name: str, package: str, source: str, modules=MODULES
                   ) -> tuple[set[str], set[str]]:
    """(imported, launched): the project modules the source of module ``name`` (in package
    ``package``) imports anywhere (in functions too: every name of every import, and every
    module named in a string, :func:`_named_in_strings`), and those it starts as a child
    process (``-m``). A child process is no import: it counts for the floors, not for the
    circles."""
    imported, launched = set(), set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            # each name is a submodule, or a name in the module (or the closest package)
            imported |= {_closest(f"{module}.{a.name}", modules) for a in node.names}
        elif isinstance(node, ast.Import):
            imported |= {_closest(a.name, modules) for a in node.names}
    for module, _, launch in _named_in_strings(source):
        (launched if launch else imported).add(_closest(module, modules))
    return ({m for m in imported if m and m != name}, {m for m in launched if m and m != name})


def _imports_of(name: str, package: str, source: str, modules=MODULES) -> set[str]:
    """The project modules module ``name`` imports (:func:`_references_of`'s first set)."""
    return _references_of(name, package, source, modules)[0]


def _references(name: str, path: Path) -> tuple[set[str], set[str]]:
    """:func:`_references_of` for module ``name`` and its file."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    return _references_of(name, package, path.read_text())


REFERENCES = {name: _references(name, path) for name, path in MODULES.items()}
#: Imports only (the circles); LAUNCHES: the modules each starts as a child process.
GRAPH = {name: refs[0] for name, refs in REFERENCES.items()}
LAUNCHES = {name: refs[1] for name, refs in REFERENCES.items()}


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


def _unit(module: str, depth: int = 3) -> str:
    """The unit a module belongs to: the module or subpackage of its first ``depth - 1``
    package levels (depth 3: ``treeimpact.compare.studies`` for
    treeimpact.compare.studies.sweep.run; depth 4: ``treeimpact.compare.studies.sweep``)."""
    return ".".join(module.split(".")[:depth])


def _unit_graph(graph: dict[str, set[str]], depth: int = 3) -> dict[str, set[str]]:
    """The import graph between units (a package-level circle is a circle here)."""
    units: dict[str, set[str]] = {}
    for module, deps in graph.items():
        units.setdefault(_unit(module, depth), set()).update(
            _unit(d, depth) for d in deps if _unit(d, depth) != _unit(module, depth))
    for deps in list(units.values()):
        for d in deps:
            units.setdefault(d, set())
    return units


def _units_inside(graph: dict[str, set[str]], package: str) -> dict[str, set[str]]:
    """The import graph between the units of ``package`` (its modules and subpackages, each
    one node), from the imports between the modules inside it."""
    inside = {m: {d for d in deps if d.startswith(package + ".")}
              for m, deps in graph.items() if m.startswith(package + ".")}
    return _unit_graph(inside, package.count(".") + 2)


#: The project's packages below treeimpact (each has units: its modules and subpackages).
PACKAGES = sorted(n for n, p in MODULES.items() if p.name == "__init__.py" and "." in n)


def test_no_circle_between_packages():
    """No circle between the units of a package either (sweep/ and report/, a study and
    report/...), function-level imports included: each subpackage is one node."""
    assert _cycles(_unit_graph(GRAPH)) == []


@pytest.mark.parametrize("package", PACKAGES)
def test_no_circle_between_the_units_of_a_subpackage(package):
    """The same inside every package at every depth (compare/report/ and its validity/,
    compare/runs/ and its bounds/, compare/studies/ and its sweep/): each of its subpackages
    is one node among its modules."""
    assert _cycles(_units_inside(GRAPH, package)) == []


def test_a_circle_between_packages_is_found():
    """Two modules of one subpackage that import a third module each way round form a
    circle at the package level, though not between modules."""
    graph = {"t.c.sweep.study": {"t.c.report.base"}, "t.c.report.base": set(),
             "t.c.report": {"t.c.sweep.run"}, "t.c.sweep.run": set()}
    assert _cycles(graph) == []
    assert _cycles(_unit_graph(graph)) == [["t.c.report", "t.c.sweep"]]
    def inside(m: str) -> str:  # the same modules one package deeper, in t.c.x
        return m.replace("t.c.", "t.c.x.", 1)

    nested = {inside(m): {inside(d) for d in deps} for m, deps in graph.items()}
    assert _cycles(_units_inside(nested, "t.c.x")) == [["t.c.x.report", "t.c.x.sweep"]]


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


def _upward(module: str, deps) -> list[str]:
    """The dependencies among ``deps`` that module ``module`` may not have, one message
    each: analytic imports neither engine nor compare; an engine package imports analytic
    only; inside analytic and inside compare no module names a higher floor
    (ANALYTIC_FLOORS, COMPARE_FLOORS)."""
    top, floor = _layer(module)
    out = []
    for dep in sorted(deps):
        dep_top, dep_floor = _layer(dep)
        if (top == "analytic" and dep_top != "analytic") or (
                top in ENGINES and dep_top not in ("analytic", top)):
            out.append(f"{module} imports {dep}")
        elif top in ("analytic", "compare") and dep_top == top and dep_floor > floor:
            out.append(f"{module} (floor {floor + 1}, {_floor_name(top, floor)}) names {dep} "
                       f"(floor {dep_floor + 1}, {_floor_name(top, dep_floor)})")
    return out


@pytest.mark.parametrize("module", sorted(MODULES))
def test_dependencies_flow_one_way(module):
    """No import, module named in a string, or child process started with ``-m`` goes
    against the flow (:func:`_upward`)."""
    assert _upward(module, GRAPH[module] | LAUNCHES[module]) == []


#: Today's two upward edges before issue 42 (pool.py preloaded floor 3 by name; study_job.py
#: started the command line): the finder must see both, and the floor check refuse both.
_UPWARD_BEFORE = {
    "treeimpact.compare.runs.pool": (
        'FORKSERVER_PRELOAD = ("treeimpact.compare.runs.cache", '
        '"treeimpact.compare.studies.ident_fits",\n'
        '                      "treeimpact.compare.studies.ident_records")\n'),
    "treeimpact.compare.report.validity.study_job": (
        'import sys\n'
        'argv = [sys.executable, "-m", "treeimpact.compare.interface.cli", "sweep"]\n'),
}


def test_the_floor_check_refuses_the_upward_edges_of_before():
    """The check above can fail: pool.py's old preload names (floor 1 naming floor 3) and
    study_job.py's old command line (floor 4 starting floor 5) are refused."""
    pool, job = (_references_of(m, m.rpartition(".")[0], src)
                 for m, src in _UPWARD_BEFORE.items())
    assert pool == ({"treeimpact.compare.runs.cache", "treeimpact.compare.studies.ident_fits",
                     "treeimpact.compare.studies.ident_records"}, set())
    assert job == (set(), {"treeimpact.compare.interface.cli"})
    assert len(_upward("treeimpact.compare.runs.pool", pool[0])) == 2
    assert _upward("treeimpact.compare.report.validity.study_job", job[1]) == [
        "treeimpact.compare.report.validity.study_job (floor 4, report) names "
        "treeimpact.compare.interface.cli (floor 5, interface)"]


def _top_level_names(path: Path) -> set[str]:
    """The names a module defines or imports at its top level, and the strings of its
    top-level tables (a lazy ``__getattr__``'s names)."""
    out = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            out |= {(a.asname or a.name).split(".")[0] for a in node.names}
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            out |= {t.id for t in targets if isinstance(t, ast.Name)}
            out |= {c.value for c in ast.walk(node) if isinstance(c, ast.Constant)
                    and isinstance(c.value, str)}
    return out


def _unresolved(source: str, modules=MODULES) -> list[str]:
    """The names in the strings of ``source`` (:func:`_named_in_strings`) that are not a
    module of the package, or whose ``:function`` that module does not define."""
    out = []
    for module, function, _ in _named_in_strings(source):
        if module not in modules:
            out.append(module)
        elif function and function not in _top_level_names(modules[module]):
            out.append(f"{module}:{function}")
    return out


@pytest.mark.parametrize("module", sorted(MODULES))
def test_every_module_named_in_a_string_exists(module):
    """A renamed module fails here, not silently (a forkserver ignores a preload it cannot
    import; importlib's ``module:function`` and ``-m`` fail only when run)."""
    assert _unresolved(MODULES[module].read_text()) == []


def test_a_misspelled_name_in_a_string_is_found():
    """The check above can fail: a misspelled module, a missing function, a ``-m`` of a
    module that is not there."""
    source = ('PRELOAD = ("treeimpact.compare.studies.ident_fitz",)\n'
              'RUN = "treeimpact.compare.runs.cache:no_such_function"\n'
              'ARGV = ["-m", "treeimpact.compare.clli"]\n')
    assert sorted(_unresolved(source)) == ["treeimpact.compare.clli",
                                           "treeimpact.compare.runs.cache:no_such_function",
                                           "treeimpact.compare.studies.ident_fitz"]


def test_the_architecture_page_states_each_floor_of_compare():
    """docs/architecture.md gives each floor of :data:`COMPARE_FLOORS` one numbered line,
    bottom first, naming its folder, with the role its comment above states (a floor
    added, removed, reordered or reworded on one side only fails here)."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    section = text.split("## compare/, bottom first")[1].split("\n## ")[0]
    documented = re.findall(r"^(\d)\. `(\w+)/`: (.+)$", section, re.M)
    source = Path(__file__).read_text().split("COMPARE_FLOORS = (\n")[1].split("\n)\n")[0]
    commented = re.findall(r"^    # (\d) (\w+)/: (.+)$", source, re.M)
    assert [u for _, u, _ in commented] == [unit for (unit,) in COMPARE_FLOORS]
    assert documented == commented


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


def test_every_package_folder_is_registered():
    """Each top-level folder holding an __init__.py is one of :data:`FOLDERS` (an engine's
    through its registration, compare.runs.backends.register_engine), tooling aside: an engine
    folder not registered, or registered but not in pyproject.toml's package list (the test
    above), fails here (docs/engines.md, "Adding an engine")."""
    tooling = {"tests", "benchmarks", "examples"}
    found = {p.parent.name for p in ROOT.glob("*/__init__.py")} - tooling
    assert found == set(FOLDERS)


#: The package data the wheel carries: source folder -> patterns of files in it.
PACKAGE_DATA = {"analytic/model": ["scenarios/*.toml"], "compare/runs": ["tolerances.toml"],
                "compare/report": ["templates/*.j2", "data/*.json"],
                "mujoco_models": ["models/*.xml"], "bullet_models": ["models/*.urdf"]}


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel built from a copy of the checkout (offline: no build isolation, no index;
    the checkout itself is left without a build/ folder)."""
    import shutil

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
    (path,) = dist.glob("treeimpact-*.whl")
    return path


@pytest.fixture(scope="module")
def wheel_files(wheel) -> set[str]:
    """The files of :func:`wheel`."""
    import zipfile

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


#: Run by the wheel's venv: where treeimpact and the trunk data were found, and the trunk
#: section rendered (markdown) from the installed package's data.
_RENDER_TRUNKS = """
import json, treeimpact
from treeimpact.compare.report.trunks import TRUNKS_JSON, TrunksSection
section = TrunksSection(tree="central-leader")
print(json.dumps({"package": treeimpact.__file__, "data": str(TRUNKS_JSON),
                  "available": section.available, "md": section.render("md")}))
"""


def test_the_installed_wheel_renders_the_trunk_section_from_its_own_data(wheel, tmp_path):
    """The wheel installed into a fresh venv outside the checkout (its dependencies from
    this venv's site-packages by a .pth line, nothing downloaded), run from a directory
    outside the checkout: the trunk section finds its data in the installed package and
    renders the same page as the checkout's."""
    import json
    import sysconfig

    from treeimpact.compare.report.trunks import TrunksSection

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True,
                   timeout=120)
    python = venv / "bin" / "python"
    proc = subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install",
                           "--no-deps", "--no-index", "-q", str(wheel)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    site = Path(subprocess.run([python, "-c", "import sysconfig; print(sysconfig."
                                "get_paths()['purelib'])"], capture_output=True, text=True,
                               check=True).stdout.strip())
    # a plain path line: this venv's packages after the fresh one's, and not its .pth files
    # (the editable install's finder would put the checkout first)
    (site / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    cwd = tmp_path / "elsewhere"
    cwd.mkdir()
    proc = subprocess.run([python, "-I", "-c", _RENDER_TRUNKS], cwd=cwd, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert Path(out["package"]).is_relative_to(site)  # the wheel's, not the checkout's
    assert Path(out["data"]).is_relative_to(site) and out["available"]
    assert out["md"] == TrunksSection(tree="central-leader").render("md")  # the checkout's
    plain = out["md"].replace("`", "").replace("**", "")
    assert plain.count(": use --trunk ") == 3 and "is not in this checkout" not in plain  # a
    # sentence per shipped tree: the numbers are there (test_report reads them back)


def test_installed_the_project_is_one_top_level_package(tmp_path):
    """From a directory outside the checkout: treeimpact imports, the folders' bare names
    do not (the installed distribution adds one top-level name)."""
    code = ("import importlib, json\n"
            "import treeimpact.analytic.impact.solver, treeimpact.compare.interface.cli\n"
            "out = {}\n"
            f"for name in {tuple(f for f in FOLDERS if f != 'treeimpact')!r}:\n"
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


def test_the_public_api_is_one_plain_module_of_re_exports():
    """The public names are treeimpact.api's (issue 51 item 3): a module of from-imports
    that defines nothing of its own, and ``treeimpact`` hands exactly those names on (no
    list of its own)."""
    import ast

    import treeimpact
    import treeimpact.api as api

    tree = ast.parse((ROOT / "treeimpact" / "api.py").read_text())
    kinds = {type(node) for node in tree.body}
    assert kinds <= {ast.Expr, ast.ImportFrom, ast.Assign}, kinds  # docstring, imports, __all__
    assert treeimpact.__all__ == api.__all__ and len(api.__all__) == len(set(api.__all__))
    for name in api.__all__:
        value = getattr(api, name)
        assert getattr(value, "__module__", "") != "treeimpact.api", name  # defined elsewhere
        assert getattr(treeimpact, name) is value, name


def test_importing_treeimpact_loads_no_implementation():
    """``import treeimpact`` is cheap: its names load on first use (the CLI's start-up)."""
    code = ("import sys, treeimpact; "
            "print(sorted(m for m in sys.modules if m.startswith('treeimpact')))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60, cwd=ROOT)
    assert proc.stdout.strip() == "['treeimpact']", proc.stdout + proc.stderr
