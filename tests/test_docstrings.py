"""Every public function, class and method of the installed package has a docstring that
names its parameters (issue 34 item 4; the public API's stricter Google-style check is
tests/test_api.py).

The walk reads each module's source with :mod:`ast` (nothing is imported): the folders and
subpackages pyproject.toml's ``[tool.setuptools]`` installs as ``treeimpact``.

Public means: a name not starting with ``_``, defined at a module's top level (also under
``if``/``try``/``with``) or in the body of a public class (nested public classes too), in a
module whose dotted name has no part starting with ``_``; and, in a ``_private`` module, a
name that its package's ``__init__`` re-exports (listed in ``__all__``, directly or through a
module-level tuple or list such as the engines' ``_RUNNER``), with the public methods of a
re-exported class.

The rule, for each public function or method:

* it has a docstring (a class too);
* every parameter (``self`` and ``cls`` aside; ``*args`` and ``**kwargs`` by their bare
  names) is named in it as a word: in running text (``restitution e``, ````mode````) or as an
  ``Args:`` entry. A one-letter name does not count when it only appears as ``e.g.`` or
  ``i.e.``. A class's ``__init__`` parameters may instead be named in the class's docstring
  (Google style puts a constructor's arguments there).

Excluded, with the reason:

* dunder methods other than ``__init__`` (``__call__``, ``__getattr__``, ``__post_init__``,
  ``__iter__``...): Python's protocols, whose meaning the protocol fixes;
* ``test_*.py`` modules and ``conftest.py`` (pytest's files that ship inside ``compare/``):
  test functions are named for the physics they check, and pytest hooks have pytest's
  documented signatures;
* functions defined inside functions, and the members of private (``_``) classes: not
  reachable by a user;
* enum members, constants and dataclass fields: assignments, not functions; their
  documentation is the ``#:`` comment or the class's ``Attributes`` (tests/test_api.py checks
  the public API's);
* a property's ``.setter``/``.deleter`` and an ``@overload`` stub: the getter or the
  implementation carries the docstring.
"""

from __future__ import annotations

import ast
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Decorators whose function is excluded (see the module docstring).
_EXCUSED_DECORATORS = ("setter", "deleter", "overload")


def _packages() -> dict[str, Path]:
    """Each installed package's dotted name -> its folder, from pyproject.toml."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    dirs = config["package-dir"]
    out = {}
    for name in config["packages"]:
        top = max((k for k in dirs if name == k or name.startswith(k + ".")), key=len)
        rest = name[len(top):].lstrip(".")
        out[name] = ROOT / dirs[top] / Path(*rest.split(".")) if rest else ROOT / dirs[top]
    return out


PACKAGES = _packages()


def _modules() -> dict[str, Path]:
    """Every module of the installed package (test modules and conftests aside) -> file."""
    out = {}
    for package, folder in PACKAGES.items():
        for path in sorted(folder.glob("*.py")):
            stem = path.stem
            if stem.startswith("test_") or stem == "conftest":
                continue
            out[package if stem == "__init__" else f"{package}.{stem}"] = path
    return out


MODULES = _modules()


def _top_level(body: list[ast.stmt]):
    """The statements of a module or class body, looking inside if/try/with blocks."""
    for node in body:
        if isinstance(node, (ast.If, ast.Try, ast.With)):
            blocks = [node.body, getattr(node, "orelse", []), getattr(node, "finalbody", [])]
            blocks += [h.body for h in getattr(node, "handlers", [])]
            for block in blocks:
                yield from _top_level(block)
        else:
            yield node


def _names(node: ast.expr, tuples: dict[str, ast.expr]) -> set[str]:
    """The strings of a literal list/tuple (``*NAME`` of a module-level tuple expanded)."""
    out = set()
    for elt in getattr(node, "elts", []):
        if isinstance(elt, ast.Constant) and isinstance(elt.value, str):
            out.add(elt.value)
        elif isinstance(elt, ast.Starred) and isinstance(elt.value, ast.Name):
            out |= _names(tuples.get(elt.value.id), tuples)
    return out


def _reexported(package: str) -> set[str]:
    """The names a package's ``__init__`` re-exports: its ``__all__``, with the module-level
    tuples it unpacks into it."""
    tree = ast.parse(MODULES[package].read_text())
    assigned = {}
    for node in _top_level(tree.body):
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                if isinstance(t, ast.Name) and node.value is not None:
                    assigned[t.id] = node.value
    return _names(assigned.get("__all__"), assigned)


def _is_private_module(name: str) -> bool:
    return any(part.startswith("_") for part in name.split(".") if part != "__init__")


@dataclass(frozen=True)
class Finding:
    """One public definition that breaks the rule: where, what, and why."""

    qualname: str
    line: int
    problem: str

    def __str__(self) -> str:
        return f"{self.qualname} (line {self.line}): {self.problem}"


_ONE_LETTER_ABBREVIATION = r"(?!\.[a-z]\.)"


def _named(name: str, text: str) -> bool:
    """Whether ``name`` appears in ``text`` as a word (``e.g.``/``i.e.`` don't count)."""
    tail = _ONE_LETTER_ABBREVIATION if len(name) == 1 else ""
    return re.search(rf"(?<![\w.]){re.escape(name)}(?!\w){tail}", text) is not None


def _parameters(func: ast.FunctionDef | ast.AsyncFunctionDef, method: bool) -> list[str]:
    a = func.args
    names = [p.arg for p in a.posonlyargs + a.args + a.kwonlyargs]
    names += [p.arg for p in (a.vararg, a.kwarg) if p is not None]
    if method and a.posonlyargs + a.args and names[0] in ("self", "cls", "mcs", "metacls"):
        names = names[1:]
    return names


def _excused(func: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    for d in func.decorator_list:
        d = d.func if isinstance(d, ast.Call) else d
        if isinstance(d, ast.Attribute) and d.attr in _EXCUSED_DECORATORS:
            return True
        if isinstance(d, ast.Name) and d.id in _EXCUSED_DECORATORS:
            return True
    return False


def _problem(func, method: bool, class_doc: str) -> str | None:
    """What is wrong with a public function's or method's docstring (None: nothing)."""
    doc = ast.get_docstring(func) or ""
    params = _parameters(func, method)
    if func.name == "__init__":  # documented in the class's docstring or its own
        missing = [p for p in params if not (_named(p, doc) or _named(p, class_doc))]
    elif not doc.strip():
        return "no docstring"
    else:
        missing = [p for p in params if not _named(p, doc)]
    return f"parameters not named: {', '.join(missing)}" if missing else None


def _definitions(body: list[ast.stmt], prefix: str, method: bool = False, class_doc: str = "",
                 wanted: set[str] | None = None):
    """(qualname, node, is a method, its class's docstring) of each public definition in a
    module's or class's body; ``wanted``: only these top-level names (a private module)."""
    for node in _top_level(body):
        name = getattr(node, "name", None)
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) or (
                wanted is not None and name not in wanted):
            continue
        dunder = name.startswith("__") and name.endswith("__")
        if name.startswith("_") and not (method and name == "__init__"):
            continue  # private, or a dunder other than a class's __init__
        if not isinstance(node, ast.ClassDef) and _excused(node):
            continue
        qualname = f"{prefix}.{name}"
        yield qualname, node, method, class_doc
        if isinstance(node, ast.ClassDef) and not dunder:
            yield from _definitions(node.body, qualname, True, ast.get_docstring(node) or "")


def _findings_in(definitions) -> list[Finding]:
    """The definitions (from :func:`_definitions`) that break the rule."""
    out = []
    for qualname, node, method, class_doc in definitions:
        if isinstance(node, ast.ClassDef):
            problem = None if (ast.get_docstring(node) or "").strip() else "no docstring"
        else:
            problem = _problem(node, method, class_doc)
        if problem:
            out.append(Finding(qualname, node.lineno, problem))
    return out


def _module_definitions(module: str):
    """The public definitions of ``module`` (see :func:`_definitions`)."""
    tree = ast.parse(MODULES[module].read_text())
    wanted = _reexported(module.rpartition(".")[0]) if _is_private_module(module) else None
    return _definitions(tree.body, module, wanted=wanted)


def _findings(module: str) -> list[Finding]:
    """The public definitions of ``module`` that break the rule."""
    return _findings_in(_module_definitions(module))


@pytest.mark.parametrize("module", sorted(MODULES))
def test_every_public_function_has_a_docstring_naming_its_parameters(module):
    findings = _findings(module)
    assert not findings, f"{len(findings)} undocumented in {module}:\n" + "\n".join(
        map(str, findings))


def test_the_walk_sees_the_whole_package():
    """The walk finds every package pyproject.toml installs, the engines' re-exports and a
    known public function (a walk that finds nothing would pass the test above)."""
    assert set(PACKAGES) <= {m for m in MODULES}
    assert {"simulate", "run", "modes"} <= _reexported("treeimpact.mujoco_models")
    assert {"simulate", "run", "modes"} <= _reexported("treeimpact.bullet_models")
    tree = ast.parse(MODULES["treeimpact.compare.interface.api"].read_text())
    assert "simulate" in {getattr(n, "name", None) for n in tree.body}
    assert len(MODULES) > 100


def test_the_rule_flags_what_it_should():
    """The checker on small sources: a missing docstring, an unnamed parameter, ``e.g.`` not
    counting as ``e``, and a constructor documented in its class."""
    src = '''
def bare(x): pass
def unnamed(e, mass):
    """Something, e.g. a weight."""
def good(e, mass, *args, **kwargs):
    """Restitution e and the ``mass`` (kg); args and kwargs pass on."""
class Pad:
    """A pad of stiffness k (N/m)."""
    def __init__(self, k): pass
    def __repr__(self): pass
    def force(self, delta): pass
class _Hidden:
    def anything(self, z): pass
'''
    got = [str(f) for f in _findings_in(_definitions(ast.parse(src).body, "m"))]
    assert got == ["m.bare (line 2): no docstring",
                   "m.unnamed (line 3): parameters not named: e, mass",
                   "m.Pad.force (line 11): no docstring"]
