"""conftest.py's rule for the tests `make test` reruns under other OpenBLAS kernels (issue 39
item 3): a test is ``numerics`` when a number it checks passes through LAPACK or BLAS. The
kernel passes collect the NUMERICS files only; a test of theirs marked ``blas_free`` is run
under a probe that fails it if it reaches the linear algebra; and a test file outside them
that calls the exact solvers says here why another kernel cannot move what it checks."""

from __future__ import annotations

import ast
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
conftest = sys.modules["conftest"]  # the root conftest.py pytest loaded (prepend mode)

#: The modules of the exact solvers (the brief's "analytic/contact, analytic/continuum").
SOLVERS = ("treeimpact.analytic.continuum", "treeimpact.analytic.contact")
#: The test files outside NUMERICS whose tests call the exact solvers, and why a kernel's
#: round-off (benchmarks/results/kernels.json: the soft SDOF's metrics move by 1e-12 at
#: most, the beam's by 3.4e-9 at 12 elements and 8.4e-7 at 48, the engines' by 1e-12 or
#: not at all) cannot cross what they check.
NOT_RERUN = {
    "tests/test_pendulum_bounds.py": "Bullet's runs at dt, dt / 2 and dt / 4 and scalar "
                                     "closed forms: the engine's stepping calls no BLAS",
    "compare/tests/test_design.py": "a design cell against the same rungs run directly in "
                                    "the same process: both sides on one kernel",
    "compare/tests/test_design_tree.py": "the designer's choice against the same rungs run "
                                         "directly in the same process (both sides on one "
                                         "kernel), closed forms to 1e-9",
    "compare/tests/test_sensitivity.py": "the study's gaps against the beam run directly in "
                                         "the same process: both sides on one kernel",
    "compare/tests/test_sweep.py": "a validity map against the soft SDOF run in the same "
                                   "process, and bands of 1.5 %",
    "compare/tests/test_ladder.py": "the rung ids default_segments names (test_chain.py, "
                                    "NUMERICS, checks its choice)",
    "compare/tests/test_mechanism.py": "the soft SDOF's matched restitution to 1e-6 (its "
                                       "metrics move by 1e-12) and a one-line refusal",
    "tests/test_budget.py": "the cost model's estimates, within a factor of two",
    "tests/test_family.py": "regimes (whether T0 and t_sep exist), exit codes, one-line "
                            "refusals and which cells exist: no number a kernel's round-off "
                            "(1e-12 relative) could move across",
    "tests/test_bullet_models.py": "Bullet against the chain's matrices at 1e-12 (one "
                                   "product's round-off, 2e-16), the soft SDOF at 0.5 %, "
                                   "convergence orders",
    "tests/test_mujoco_models.py": "MuJoCo against the chain's matrices at 1e-12 (one "
                                   "product's round-off), the soft SDOF at 0.5 %, the beam "
                                   "at 1e-4 and convergence orders",
    "tests/test_mujoco_flex.py": "MuJoCo's flex against the beam at 1 % and 2 %",
    "tests/test_contact_fit.py": "the fit of a contact it generated: finite values, which "
                                 "targets it explains, bounds flagged",
    "tests/test_identify_procedure_events.py": "contact onsets read from a soft record to "
                                               "one sample",
    "tests/test_numerics_rule.py": "whether the chain's modes reach LAPACK, not their values",
    "tests/test_bounds.py": "the modes' sum against the static flexibility at 1e-6 and the "
                            "shear's delta against its closed form at 1e-9, both sides on "
                            "one kernel",
    "compare/tests/test_findings.py": "the derived bands against the same masses and runs "
                                      "recomputed in the same process (both sides on one "
                                      "kernel) and verdicts inside bands of several %",
}


def _calls_a_solver(path: Path) -> bool:
    """Whether a test function of ``path`` uses a name imported from :data:`SOLVERS`."""
    tree = ast.parse(path.read_text())
    names = {a.asname or a.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
             and (node.module or "").startswith(SOLVERS) for a in node.names}
    return any(isinstance(f, ast.FunctionDef) and f.name.startswith("test_") and (
        {n.id for n in ast.walk(f) if isinstance(n, ast.Name)} & names or any(
            isinstance(n, ast.ImportFrom) and (n.module or "").startswith(SOLVERS)
            for n in ast.walk(f))) for f in tree.body)


def test_every_test_file_calling_the_exact_solvers_is_rerun_or_says_why_not():
    files = sorted(p.relative_to(ROOT).as_posix() for p in [
        *ROOT.glob("tests/test_*.py"), *ROOT.glob("compare/tests/test_*.py")])
    calling = {f for f in files if _calls_a_solver(ROOT / f)}
    assert calling - conftest.NUMERICS - set(NOT_RERUN) == set(), "add to NUMERICS or NOT_RERUN"
    assert set(NOT_RERUN) <= calling, "NOT_RERUN names a file that calls no solver"
    assert "tests/test_beam_impact.py" in calling & conftest.NUMERICS  # the scan sees a call


def _reached(func) -> list:
    reached: list = []
    previous = sys.getprofile()
    sys.setprofile(conftest._linalg_probe(reached, conftest._linalg_roots()))
    try:
        func()
    finally:
        sys.setprofile(previous)
    return reached


def test_the_probe_sees_lapack_blas_and_the_project_s_matrix_products():
    import scipy.linalg

    from treeimpact.analytic.continuum.chain import chain_natural_frequencies, hinged_chain
    from treeimpact.analytic.model.scenario import load_scenario

    a = np.array([[2.0, 1.0], [1.0, 3.0]])
    trunk = load_scenario("open-center").trunk
    assert _reached(lambda: np.linalg.solve(a, [1.0, 2.0]))
    assert _reached(lambda: scipy.linalg.expm(a))
    assert _reached(lambda: a.dot(a))
    assert _reached(lambda: chain_natural_frequencies(hinged_chain(trunk, 4), 2))
    # elementwise arithmetic, reductions and math are no linear algebra
    assert _reached(lambda: (np.exp(a) * a).sum() + math.sin(1.0)) == []


def test_the_kernel_passes_collect_the_numerics_files_among_those_given():
    every = sorted(conftest.NUMERICS)
    assert conftest.numerics_files(["tests", "compare"]) == every
    assert conftest.numerics_files(["."]) == conftest.numerics_files([str(ROOT / "tests")])
    assert conftest.numerics_files(["compare"]) == []
    assert conftest.numerics_files(["tests/test_beam.py::test_x", "tests/test_docs.py"]) == [
        "tests/test_beam.py::test_x"]
    assert all((ROOT / f).is_file() for f in every)


def test_a_mark_outside_the_numerics_files_is_named():
    def item(rel, *marks):
        return SimpleNamespace(path=ROOT / rel,
                               get_closest_marker=lambda name: name in marks or None)

    items = [item("tests/test_beam.py", "numerics"), item("tests/test_docs.py"),
             item("tests/test_paper.py", "numerics"), item("tests/test_bad_input.py",
                                                           conftest.BLAS_FREE)]
    assert conftest.check_numerics(items) == ["tests/test_bad_input.py", "tests/test_paper.py"]
