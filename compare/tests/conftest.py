"""pytest configuration of ``pytest compare``.

* Runs are shared by every test through this session's :data:`SESSION_CACHE` (fixture
  ``run_cache``, passed explicitly) and the ladders built from it (fixture ``ladder_of``):
  each (scenario, backend, options) is simulated once per session.
* ``--report DIR`` writes the discrepancy report (report.html, report.md, report.json) into
  DIR at the end of the session, from the same runs.
* A failing cross-check prints a compact table (metric, every rung's value, the compared
  pair, relative difference, tolerance, verdict, reason) instead of a traceback; see
  :func:`assert_checks`.
"""

from __future__ import annotations

import pytest

from treeimpact.compare.runs import DIVERGED, FAILED, SKIPPED, RunCache

#: The session's runs: every test, the ladders and ``--report DIR`` share them.
SESSION_CACHE = RunCache()


def pytest_addoption(parser):
    parser.addoption("--report", metavar="DIR", default=None,
                     help="also write the discrepancy report (report.html, .md, .json) into "
                          "DIR from the runs of this session")


@pytest.fixture(scope="session")
def run_cache():
    return SESSION_CACHE


_LADDERS: dict = {}


@pytest.fixture(scope="session")
def ladder_of(run_cache):
    """ladder_of(name) -> the scenario's :class:`compare.ladder.Ladder`, built once."""
    from treeimpact.compare.ladder import build_ladder

    def get(name):
        if not _LADDERS:  # first use: every shipped ladder's runs at once, on a process pool
            from treeimpact.analytic.model.scenario import shipped_scenarios
            from treeimpact.compare.ladder import prefetch_ladders

            prefetch_ladders(run_cache, list(shipped_scenarios()))
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


def assert_checks(ladder, checks) -> None:
    """Pass when every check's verdict passes (compare.verdicts.Verdict.passes: ``ok``, a
    ``finding`` in its band, or a peak time flagged ``ambiguous``, x(t) with two near-equal
    maxima, not judged by the documented rule; test_ladder checks which rungs are); else
    print the table."""
    from treeimpact.compare.ladder import failure_table

    bad = [c for c in checks if not c.verdict.passes]
    if bad:
        pytest.fail("\n" + failure_table(ladder, checks), pytrace=False)


def pytest_sessionfinish(session, exitstatus):
    out = session.config.getoption("--report", default=None)
    if not out:
        return
    from treeimpact.compare.report import write_report

    paths = write_report(out, runs=SESSION_CACHE)
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.ensure_newline()
        reporter.write_line(f"discrepancy report: {paths['html']} ({paths['md'].name}, "
                            f"{paths['json'].name})")
