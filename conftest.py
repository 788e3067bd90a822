"""Root pytest configuration shared by `tests` and `compare`.

OpenBLAS starts one thread per core for every small matrix operation; on the 2-core CI
machine those threads fight the test process itself and each call costs ~1 s. The suite
only handles matrices of a few hundred rows, so one BLAS thread is the fast choice.

The project installs one top-level package, `treeimpact`; an import of its folders by their
bare names (`analytic`, `compare.tree.ladder`) fails here, so a test cannot pass on a second copy.

The tests whose numbers depend on BLAS and LAPACK round-off are marked ``numerics``
(:data:`NUMERICS`): `make test` runs them again under two other machines' OpenBLAS kernels
(tests/blas_kernels.py; docs/reproducibility.md).
"""

import functools
import importlib.abc
import inspect
import os
import re
import sys
from pathlib import Path

import pytest

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")


class _NoBareNames(importlib.abc.MetaPathFinder):
    """Refuse an import of the project's folders by their bare names (``analytic``,
    ``compare.tree.ladder``, ...): installed they are subpackages of ``treeimpact`` only, and a
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


#: The test files whose tests are ``numerics``: the rule is that a test is ``numerics`` when
#: a number it checks passes through LAPACK or BLAS (numpy.linalg, scipy.linalg and
#: scipy.optimize, the exact solvers' eigen-decompositions, matrix exponentials and linear
#: solves, the fits' least squares), where another kernel's round-off could move it: the beam
#: and its impact, the whole event, the hinged chain, the modes and Timoshenko's beam, the
#: exact solver and the soft contact, the record fit, the engines' modes, the numbers checks,
#: the exact rungs' equivalence with the baseline (not the reduction's symbolic algebra nor
#: the generated files' text: no linear algebra). Each of their tests is,
#: except those marked ``blas_free`` (:data:`BLAS_FREE`: they check text, interfaces or an
#: engine's own arithmetic; :func:`pytest_runtest_call` fails one that reaches the linear
#: algebra). No test outside these files may carry the mark (:func:`check_numerics`): the
#: kernel passes collect these files only (:func:`numerics_files`, the Makefile's ``test``).
NUMERICS = frozenset({
    "tests/test_beam.py", "tests/test_beam_impact.py", "tests/test_whole_event.py",
    "tests/test_chain.py", "tests/test_timoshenko.py", "tests/test_solver.py",
    "tests/test_soft_contact.py", "tests/test_record_fit.py",
    "tests/test_engine.py", "tests/test_doc_numbers.py", "tests/test_exact_equivalence.py",
    "tests/test_billet_rungs.py",
})
#: The mark of a test in a :data:`NUMERICS` file that checks no number through the linear
#: algebra, so gains nothing from a rerun under another kernel.
BLAS_FREE = "blas_free"
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
    config.addinivalue_line("markers", f"{BLAS_FREE}: a test of a NUMERICS file that checks "
                            "no number through LAPACK/BLAS (conftest.py), not rerun under "
                            "other kernels")


def numerics_files(paths=("tests", "compare")) -> list[str]:
    """The :data:`NUMERICS` files (or node ids ``file::test`` of them) among ``paths``
    (folders, files or node ids from the repository's root, as `make test`'s ``TESTS``):
    what the kernel passes collect, so that they import no other test module."""
    out = []
    for rel in sorted(NUMERICS):
        for given in paths:
            path, sep, test = given.partition("::")
            p = _relative(_ROOT / path)  # "" outside the repository
            if p == rel and sep:
                out.append(f"{rel}::{test}")
            elif p == rel or p == "." or p and rel.startswith(p + "/"):
                out.append(rel)
                break
    return out


def check_numerics(items) -> list[str]:
    """The files outside :data:`NUMERICS` that hold a test marked ``numerics`` or
    ``blas_free`` (the kernel passes would not collect the one; the other means nothing)."""
    return sorted({_relative(i.path) for i in items if _relative(i.path) not in NUMERICS
                   and (i.get_closest_marker("numerics") or i.get_closest_marker(BLAS_FREE))})


#: A matrix product in a module's source (``A @ B``, matmul, einsum, dot): numpy's ``@`` is
#: an operator no profile hook sees, so entering such a module counts as reaching BLAS.
_PRODUCT = re.compile(r"[\w)\]] @ [\w(\[]|matmul|einsum|\.dot\(")


@functools.cache
def _linalg_roots() -> tuple[str, ...]:
    """Where :func:`_linalg_probe` counts an entry as linear algebra: the folders of
    numpy.linalg, scipy.linalg, scipy.optimize and scipy.sparse.linalg, and the project's
    modules whose source holds a matrix product (:data:`_PRODUCT`)."""
    import numpy.linalg
    import scipy.linalg
    import scipy.optimize
    import scipy.sparse.linalg

    folders = [os.path.dirname(m.__file__) + os.sep for m in (
        numpy.linalg, scipy.linalg, scipy.optimize, scipy.sparse.linalg)]
    modules = [str(f) for folder in _FOLDERS for f in (_ROOT / folder).rglob("*.py")
               if "tests" not in f.parts and _PRODUCT.search(f.read_text())]
    return (*folders, *modules)


def _linalg_probe(reached: list, roots: tuple[str, ...]):
    """A :func:`sys.setprofile` function that appends to ``reached`` each entry into the
    linear algebra: a Python function of a file under ``roots`` (:func:`_linalg_roots`; not
    the module or class bodies an import runs), or numpy's ``dot``, ``vdot`` or ``inner``."""
    def probe(frame, event, arg):
        code = frame.f_code
        if (event == "call" and code.co_flags & inspect.CO_OPTIMIZED
                and code.co_filename.startswith(roots)):  # a function, not an import's
            # module or class body (a test imports such a module on its own, not so when
            # an earlier test of its worker did: the outcome followed the order)
            reached.append(f"{code.co_filename}:{code.co_name}")
        elif event == "c_call" and getattr(arg, "__name__", "") in ("dot", "vdot", "inner"):
            reached.append(f"numpy {arg.__name__}")
    return probe


_REACHED = pytest.StashKey[list]()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    """:func:`_check_lists`; the setup of a ``blas_free`` test (its function fixtures) under
    :func:`_linalg_probe`."""
    _check_lists(item)
    if item.get_closest_marker(BLAS_FREE) is None:
        return (yield)
    item.stash[_REACHED] = []
    previous = sys.getprofile()
    sys.setprofile(_linalg_probe(item.stash[_REACHED], _linalg_roots()))
    try:
        return (yield)
    finally:
        sys.setprofile(previous)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    """Run a ``blas_free`` test under :func:`_linalg_probe`: fail it when its setup or call
    reached the linear algebra, or when it uses a module or session fixture (made once, not
    seen again): it would then belong to the kernel passes (remove its mark)."""
    if item.get_closest_marker(BLAS_FREE) is None:
        return (yield)
    reached = item.stash.setdefault(_REACHED, [])
    previous = sys.getprofile()
    sys.setprofile(_linalg_probe(reached, _linalg_roots()))
    try:
        result = yield
    finally:
        sys.setprofile(previous)
    if reached or _shared_scopes(item):
        pytest.fail(f"marked {BLAS_FREE} but reached the linear algebra "
                    f"({(reached or ['a shared fixture'])[0]}, {len(reached)} calls): "
                    "conftest.py's rule makes it numerics", pytrace=False)
    return result


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
    "compare/tests/test_small_e.py", "compare/tests/test_bounds_contact.py",
})
MODULE_FIXTURE_FILES = frozenset({
    "compare/tests/test_figure_passes.py", "compare/tests/test_figure_titles.py",
    "compare/tests/test_first_screen.py",
    "compare/tests/test_sobol_cross.py",
    "compare/tests/test_sort_keys.py", "tests/test_bullet_models.py",
    "tests/test_contact_cmd.py", "tests/test_doc_numbers.py", "tests/test_engine_phases.py",
    "tests/test_family.py",
    "tests/test_identify_procedure_events.py", "tests/test_identify_validation.py",
    "tests/test_layers.py", "tests/test_mujoco_flex.py", "tests/test_mujoco_models.py",
    "tests/test_paper.py", "tests/test_report_atomic.py",
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
_STRAY = pytest.StashKey[frozenset]()


def pytest_collection_modifyitems(config, items):
    """Mark the tests of :data:`NUMERICS` ``numerics``; note the files whose shared fixtures
    the scheduling groups miss (:func:`check_groups`), whose tests then fail at setup."""
    config.stash[_STRAY] = frozenset(check_numerics(items))
    config.stash[_STALE] = frozenset(check_groups(items))
    for item in items:
        if _relative(item.path) in NUMERICS and item.get_closest_marker(BLAS_FREE) is None:
            item.add_marker(pytest.mark.numerics)
    if {item.path for item in items} == {*_ROOT.glob("tests/test_*.py"),
                                          *_ROOT.glob("compare/tests/test_*.py")}:
        config.stash[_WHOLE] = items[:]


_WHOLE = pytest.StashKey[list]()


@pytest.fixture
def whole_suite(request) -> list | None:
    """Every test this session collected, when it collected every test file of tests/ and
    compare/tests/ (`make test`'s run and each of its workers; taken before any ``-k``/``-m``
    deselection, the ``numerics`` marks set): what ``pytest --collect-only tests compare``
    collects, so a test that asks what the suite holds needs no second collection; else
    None."""
    return request.config.stash.get(_WHOLE, None)


def _check_lists(item):
    """Fail a test of a file :func:`check_groups` found missing from the groups or
    :func:`check_numerics` outside NUMERICS (a failure, not a collection error, so that it
    reads the same under xdist's workers)."""
    rel = _relative(item.path)
    if rel in item.config.stash.get(_STRAY, frozenset()):
        pytest.fail(f"conftest.py: {rel} holds a test marked numerics or {BLAS_FREE}; add "
                    "the file to NUMERICS (the kernel passes collect its files only)",
                    pytrace=False)
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
