"""pytest configuration of ``pytest compare``.

* Runs are shared by every test through this session's :data:`SESSION_CACHE` (fixture
  ``run_cache``, passed explicitly) and the ladders built from it (fixture ``ladder_of``):
  each (scenario, backend, options) is simulated once per session.
* ``--scenario TREE`` (repeatable: a shipped name or a scenario TOML file) runs the
  cross-checks (test_cross_checks.py, and only those) on these trees instead of the shipped
  ones, under the same verdict rules (findings recognised from each tree's physics).
* ``--report DIR`` writes the discrepancy report (report.html, report.md, report.json) into
  DIR at the end of the session, from the same runs.
* A failing cross-check prints a compact table (metric, every rung's value, the compared
  pair, relative difference, tolerance, verdict, reason) instead of a traceback; see
  :func:`assert_checks`.
"""

from __future__ import annotations

import pytest

from treeimpact.compare.runs.cache import DIVERGED, FAILED, SKIPPED, RunCache

#: The session's runs: every test, the ladders and ``--report DIR`` share them.
SESSION_CACHE = RunCache()
#: The trees the cross-checks run on (``--scenario``; default every shipped one), filled in
#: by :func:`pytest_configure` before the test modules are collected.
SCENARIOS: list = []
#: Each tree's name (its test ids), by the scenario as given.
NAMES: dict = {}


def pytest_addoption(parser):
    parser.addoption("--report", metavar="DIR", default=None,
                     help="also write the discrepancy report (report.html, .md, .json) into "
                          "DIR from the runs of this session")
    parser.addoption("--scenario", metavar="TREE", action="append", default=None,
                     dest="treeimpact_scenarios",
                     help="run the cross-checks on this tree (a shipped name or a scenario "
                          "TOML file; repeatable) instead of the shipped trees")


def pytest_configure(config):
    """The trees of the cross-checks: ``--scenario``'s, each loaded now (a bad one ends the
    session at once with its one-line error, exit 2), else every shipped tree."""
    from treeimpact.analytic.errors import ParameterError, one_line
    from treeimpact.analytic.model.scenario import shipped_scenarios

    given = config.getoption("treeimpact_scenarios", default=None)
    SCENARIOS[:] = given or list(shipped_scenarios())
    for s in SCENARIOS:
        try:
            NAMES[s] = _validated(s).name
        except ParameterError as exc:
            pytest.exit(f"--scenario {s!r}: {one_line(exc)}", returncode=2)


def _validated(path):
    """The tree ``path`` loaded and run on the paper's model (the reference every rung is
    compared with): a ParameterError in one line for a file that cannot be read or is out
    of range, or a tree the reference cannot run (a t_end too short for its impact, an x_max
    beyond the clamp height): nothing could be compared on it. A rung that refuses the tree
    (the soft pad at e = 0) is the tests' to skip with its reason."""
    from treeimpact.analytic.errors import ParameterError, SimulationDiverged, one_line
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.compare.runs.backends import get_backend

    scen = load_scenario(path)
    try:
        get_backend("analytic").simulate(scen)
    except (ParameterError, SimulationDiverged) as exc:  # OutsideValidity among them
        text = one_line(exc).replace("--t-end", "t_end")  # the file's field, not a flag here
        raise ParameterError(f"the paper's model (analytic), every rung's reference, cannot "
                             f"run this tree: {text}") from None
    return scen


def pytest_collection_modifyitems(config, items):
    """With ``--scenario``, only the cross-checks run (the other tests check the code on the
    shipped trees, not the user's)."""
    if not config.getoption("treeimpact_scenarios", default=None):
        return
    keep = [i for i in items if i.path.name == "test_cross_checks.py"]
    if len(keep) != len(items):
        config.hook.pytest_deselected(items=[i for i in items if i not in keep])
        items[:] = keep


@pytest.fixture(scope="session")
def run_cache():
    return SESSION_CACHE


_LADDERS: dict = {}


@pytest.fixture(scope="session")
def ladder_of(run_cache):
    """ladder_of(name) -> the scenario's :class:`compare.tree.ladder.Ladder`, built once."""
    from treeimpact.compare.tree.ladder import build_ladder

    def get(name):
        if not _LADDERS:  # first use: every session tree's runs at once, on a process pool
            from treeimpact.compare.tree.ladder import prefetch_ladders

            prefetch_ladders(run_cache, list(SCENARIOS))
        if name not in _LADDERS:
            _LADDERS[name] = build_ladder(name, cache=run_cache)
        return _LADDERS[name]

    return get


def require_run(ladder, rung_id: str) -> None:
    """Skip (with the reason) a rung the backend refused; fail one that crashed or diverged."""
    rr = ladder[rung_id]
    if rr.status == SKIPPED:
        pytest.skip(f"{ladder.name} {rung_id}: {rr.reason}")
    if rr.status in (FAILED, DIVERGED):
        pytest.fail(f"{ladder.name} {rung_id}: {rr.reason}", pytrace=False)


def _absent_on_both(check) -> bool:
    """A check with no value on either side: nothing to compare, not a disagreement."""
    from treeimpact.compare.runs.verdicts import Verdict

    return check.verdict is Verdict.NOT_AVAILABLE and not any(
        isinstance(v, (int, float)) and v == v for v in (check.value, check.reference_value))


def _skip_reason(ladder, check) -> str:
    """The physical reason a check of a quantity the tree's motion does not have is skipped:
    the verdict's own (compare.runs.verdicts.absent_reason), or for a check with no value on
    either side, :data:`compare.runs.verdicts.WHY_NONE`'s."""
    from treeimpact.compare.runs.verdicts import WHY_NONE, Verdict

    c = check
    if c.verdict is Verdict.SKIPPED:
        return f"{ladder.name} {c.rung}: {c.reason}"
    return (f"{ladder.name} {c.rung}: {c.metric} has no value on {c.rung} nor on "
            f"{c.reference}: {WHY_NONE.get(c.metric, 'neither run reports it')}")


def assert_checks(ladder, checks) -> None:
    """Pass when every check's verdict passes (compare.runs.verdicts.Verdict.passes: ``ok``, a
    ``finding`` in its band, or a peak time flagged ``ambiguous``, x(t) with two near-equal
    maxima, not judged by the documented rule; test_ladder checks which rungs are); skip
    (with the physical reason, compare.runs.verdicts.WHY_NONE) when the only ones that do not are
    of a quantity the tree's motion does not have (verdict ``skipped``: a user's tree,
    ``--scenario``, whose bodies never move together); else print the table."""
    from treeimpact.compare.runs.verdicts import Verdict
    from treeimpact.compare.tree.ladder import failure_table

    bad = [c for c in checks if not c.verdict.passes]
    if bad and all(c.verdict is Verdict.SKIPPED or _absent_on_both(c) for c in bad):
        pytest.skip(_skip_reason(ladder, bad[0]))
    if bad:
        pytest.fail("\n" + failure_table(ladder, checks), pytrace=False)


def pytest_sessionfinish(session, exitstatus):
    out = session.config.getoption("--report", default=None)
    if not out:
        return
    from treeimpact.compare.report import write_report

    paths = write_report(out, scenarios=list(SCENARIOS), runs=SESSION_CACHE)
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.ensure_newline()
        reporter.write_line(f"discrepancy report: {paths['html']} ({paths['md'].name}, "
                            f"{paths['json'].name})")
