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


#: `make test`'s scheduling units (``--dist loadgroup``, :func:`pytest_xdist_make_scheduler`):
#: every test of one of these files runs on the same worker, so what its tests share is made
#: once, not once per worker; the tests of the other files spread over the workers one by one.
#: :data:`SESSION_FILES`: the files whose tests use compare/tests/conftest.py's session runs
#: (``run_cache``, ``ladder_of``: every shipped tree's ladder, about a minute of engine runs),
#: one group. :data:`MODULE_FIXTURE_FILES`: the files with a module fixture (the
#: identification validation's fits, a written report, ...), a group each. A static list,
#: since xdist's controller schedules before any worker has collected; the collection checks
#: it against the fixtures the tests use (:func:`check_groups`).
SESSION_GROUP = "session-runs"
SESSION_FILES = frozenset({
    "compare/tests/test_cross_checks.py", "compare/tests/test_ladder.py",
    "compare/tests/test_mechanism.py", "compare/tests/test_report.py",
    "compare/tests/test_small_e.py",
})
MODULE_FIXTURE_FILES = frozenset({
    "compare/tests/test_figure_passes.py", "compare/tests/test_figure_titles.py",
    "compare/tests/test_sobol_cross.py",
    "compare/tests/test_sort_keys.py", "tests/test_bullet_models.py",
    "tests/test_contact_cmd.py", "tests/test_doc_numbers.py",
    "tests/test_identify_procedure_events.py", "tests/test_identify_validation.py",
    "tests/test_layers.py", "tests/test_mujoco_flex.py", "tests/test_mujoco_models.py",
    "tests/test_paper.py",
})


def group_of(rel: str) -> str | None:
    """The scheduling group of the test file ``rel`` (a path from the repository's root):
    :data:`SESSION_GROUP`, the file itself, or None (its tests scheduled one by one)."""
    if rel in SESSION_FILES:
        return SESSION_GROUP
    return rel if rel in MODULE_FIXTURE_FILES else None


def _shared_scopes(item) -> set[str]:
    """The scopes ("session", "module", ...) of the wider-than-a-test fixtures ``item`` uses
    that the project's test folders define (pytest's own, e.g. tmp_path_factory, left out).
    Reads pytest's ``_fixtureinfo`` (pytest 8-9); without it, none."""
    info = getattr(item, "_fixtureinfo", None)
    scopes = set()
    for defs in getattr(info, "name2fixturedefs", {}).values():
        for fd in defs:
            code = getattr(fd.func, "__code__", None)
            if fd.scope != "function" and code is not None and _relative(
                    Path(code.co_filename)).startswith(("tests/", "compare/")):
                scopes.add(fd.scope)
    return scopes


def _relative(path: Path) -> str:
    """``path`` from the repository's root ("" outside it)."""
    path = Path(path).resolve()
    return path.relative_to(_ROOT).as_posix() if path.is_relative_to(_ROOT) else ""


def check_groups(items) -> list[str]:
    """The files whose tests share a fixture their :func:`group_of` does not keep on one
    worker (a session fixture outside :data:`SESSION_FILES`, a module one in neither list)."""
    stale = set()
    for item in items:
        scopes, rel = _shared_scopes(item), _relative(item.path)
        if "session" in scopes and group_of(rel) != SESSION_GROUP or scopes and not group_of(rel):
            stale.add(rel)
    return sorted(stale)


_STALE = pytest.StashKey[frozenset]()


def pytest_collection_modifyitems(config, items):
    """Mark the tests of :data:`NUMERICS` ``numerics``; note the files whose shared fixtures
    the scheduling groups miss (:func:`check_groups`), whose tests then fail at setup."""
    config.stash[_STALE] = frozenset(check_groups(items))
    for item in items:
        if _relative(item.path) in NUMERICS:
            item.add_marker(pytest.mark.numerics)


def pytest_runtest_setup(item):
    """Fail a test of a file :func:`check_groups` found missing from the groups (a failure,
    not a collection error, so that it reads the same under xdist's workers)."""
    rel = _relative(item.path)
    if rel in item.config.stash.get(_STALE, frozenset()):
        pytest.fail(f"conftest.py: add {rel} to SESSION_FILES (it uses a session fixture of "
                    "compare/tests/conftest.py) or MODULE_FIXTURE_FILES (a module fixture): "
                    "make test's scheduler keeps its tests on one worker", pytrace=False)


@pytest.hookimpl(tryfirst=True, optionalhook=True)  # before xdist's own; only with xdist
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadgroup``'s scheduler with :func:`group_of`'s groups: xdist 3.8 reads its
    ``xdist_group`` marks from node ids that pytest 9.2 no longer lets it rename
    (pytest-xdist issue 1386), so the groups come from the file's path. The largest group
    (most tests) is sent first; other options: xdist's own scheduler."""
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadGroupScheduling

    class FileGroups(LoadGroupScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return group_of(nodeid.split("::", 1)[0]) or super()._split_scope(nodeid)

    return FileGroups(config, log)
