"""Root pytest configuration shared by `tests` and `compare`.

OpenBLAS starts one thread per core for every small matrix operation; on the 2-core CI
machine those threads fight the test process itself and each call costs ~1 s. The suite
only handles matrices of a few hundred rows, so one BLAS thread is the fast choice.

The project installs one top-level package, `treeimpact`; an import of its folders by their
bare names (`analytic`, `compare.ladder`) fails here, so a test cannot pass on a second copy.

The tests whose numbers depend on BLAS and LAPACK round-off are marked ``numerics``
(:data:`NUMERICS`): `make test` runs them again under two other machines' OpenBLAS kernels
(tests/blas_kernels.py; docs/reproducibility.md).
"""

import importlib.abc
import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")


class _NoBareNames(importlib.abc.MetaPathFinder):
    """Refuse an import of the project's folders by their bare names (``analytic``,
    ``compare.ladder``, ...): installed they are subpackages of ``treeimpact`` only, and a
    bare import would load a second copy of a module. pytest itself imports the tests of
    ``compare/tests/`` (not installed) as ``compare.tests.*``, their package ``compare`` first:
    those are let through."""

    def find_spec(self, fullname, path=None, target=None):
        top, _, rest = fullname.partition(".")
        if top in _FOLDERS and not (top == "compare" and (not rest or rest == "tests"
                                                          or rest.startswith("tests."))):
            raise ImportError(f"{fullname}: import it as treeimpact.{fullname} (the project "
                              "installs one top-level package, treeimpact)")
        return None


_FOLDERS = ("analytic", "compare", "mujoco_models", "bullet_models")
sys.meta_path.insert(0, _NoBareNames())


#: Test files marked ``numerics``: eigen-decompositions, matrix exponentials and linear
#: solves whose round-off moves with the BLAS kernel, feeding chattering contacts or the
#: numbers the docs print (beam and its impact, the whole event, the hinged chain, the
#: modes and Timoshenko's beam, the exact solver and the soft contact, the reduction, the
#: record fit, the engines' modes and generated model files, the numbers checks).
NUMERICS = frozenset({
    "tests/test_beam.py", "tests/test_beam_impact.py", "tests/test_whole_event.py",
    "tests/test_chain.py", "tests/test_timoshenko.py", "tests/test_solver.py",
    "tests/test_soft_contact.py", "tests/test_reduction.py", "tests/test_record_fit.py",
    "tests/test_engine.py", "tests/test_generated_files.py", "tests/test_doc_numbers.py",
})
_ROOT = Path(__file__).resolve().parent


#: The longest one pytest process may run (s) before it prints every thread's stack and
#: exits with an error: a hang (a test's thread or child that outlives it and blocks the
#: interpreter's exit) then fails `make test` in minutes, not at CI's own limit. The whole
#: suite takes about 5 minutes on 2 cores; ``TREEIMPACT_TEST_LIMIT_S`` overrides it.
TEST_LIMIT_S = 1800.0


def pytest_configure(config):
    """Start the watchdog of :data:`TEST_LIMIT_S` on a copy of the real stderr (pytest's
    capture has not taken it yet here), so the stacks reach the log wherever it hangs."""
    import faulthandler

    limit = float(os.environ.get("TREEIMPACT_TEST_LIMIT_S", TEST_LIMIT_S))
    faulthandler.dump_traceback_later(limit, exit=True, file=os.dup(2))


#: The ``xdist_group`` of every test that uses a session fixture of the project's
#: (compare/tests/conftest.py's ``run_cache`` and ``ladder_of``: every shipped tree's ladder
#: runs, about a minute of engine runs on a process pool): under `make test`'s ``--dist
#: loadgroup`` they all run on one worker, so those runs are made once, not once per worker.
SESSION_GROUP = "session-runs"


def _shared_fixtures(item) -> set[str]:
    """The scopes ("session", "module", ...) of the wider-than-a-test fixtures ``item`` uses
    that the project's own files define (pytest's, e.g. tmp_path_factory, left out). Reads
    pytest's ``_fixtureinfo`` (pytest 8-9); without it, none (no groups: the same tests run,
    a module fixture only made once per worker)."""
    info = getattr(item, "_fixtureinfo", None)
    scopes = set()
    for defs in getattr(info, "name2fixturedefs", {}).values():
        for fd in defs:
            scope = getattr(fd, "scope", "function")
            if scope == "function":
                continue
            source = Path(getattr(fd.func, "__code__", None) and fd.func.__code__.co_filename
                          or "").resolve()
            if path_under(source, ("tests", "compare")):
                scopes.add(scope)
    return scopes


def path_under(path: Path, folders) -> bool:
    """Whether ``path`` is in one of the repository's top-level ``folders``."""
    return path.is_relative_to(_ROOT) and path.relative_to(_ROOT).parts[:1] in [
        (f,) for f in folders]


def xdist_groups(items) -> dict:
    """Test file (relative path) -> its ``xdist_group``: :data:`SESSION_GROUP` for a file with
    a test that uses a project session fixture, the file itself for one with a test that uses
    a project module (or class) fixture (made once: the file stays on one worker); files of
    neither are left out (their tests spread over the workers one by one). Per file, not per
    test, so that every test of a file shares its module fixtures' single copy."""
    groups: dict = {}
    for item in items:
        scopes = _shared_fixtures(item)
        rel = Path(item.path).resolve().relative_to(_ROOT).as_posix()
        if "session" in scopes:
            groups[rel] = SESSION_GROUP
        elif scopes and groups.get(rel) != SESSION_GROUP:
            groups[rel] = rel
    return groups


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist's own hook reads the xdist_group marks
def pytest_collection_modifyitems(config, items):
    """Mark the tests of :data:`NUMERICS` ``numerics`` and give every test of a file with
    shared fixtures its ``xdist_group`` (:func:`xdist_groups`; used by ``--dist loadgroup``
    only)."""
    groups = xdist_groups(items)
    for item in items:
        path = Path(item.path).resolve()
        rel = path.relative_to(_ROOT).as_posix() if path.is_relative_to(_ROOT) else None
        if rel in NUMERICS:
            item.add_marker(pytest.mark.numerics)
        if rel in groups:
            item.add_marker(pytest.mark.xdist_group(groups[rel]))
