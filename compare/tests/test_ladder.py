"""The ladder machinery: rungs, the run cache and its skip reasons, verdicts, tolerances,
the identification floor behind the tolerance file, and the failure table."""

from __future__ import annotations

import math

import pytest

from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.identify.procedure import (
    identification_errors,
    identify_from_record,
    pendulum_test_of,
    truth_of,
)
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.options import Option
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios
from treeimpact.compare.runs import backends
from treeimpact.compare.runs.backends import Backend
from treeimpact.compare.runs.cache import DIVERGED, FAILED, OK, SKIPPED, RunCache
from treeimpact.compare.runs.findings import TreePhysics
from treeimpact.compare.runs.verdicts import judge, load_tolerances
from treeimpact.compare.tree.ladder import (
    ALL_METRICS,
    ANALYTIC_SAMPLE_STEP,
    IDENT_METRICS,
    build_ladder,
    failure_table,
    ladder_rungs,
)
from treeimpact.analytic.model.options import scenario_as_run

TOL = load_tolerances()


def test_each_rung_changes_exactly_one_assumption():
    rungs = {r.id: r for r in ladder_rungs("open-center", engines=("mujoco", "bullet"),
                                           segments=7)}
    # MuJoCo's trunk option offers its elastic rod (flex): one more rung, level 7
    assert [r.level for r in rungs.values()] == [1, 2, 3, 4, 5, 6, 7, 8, 7, 6, 7, 8]
    assert rungs["analytic"].previous is None and rungs["soft"].previous == "analytic"
    # the trunk alone: the beam backend takes the soft SDOF's pad (k_c, c_c) by default
    assert rungs["beam"].previous == "soft" and rungs["beam"].options == ()
    theory = rungs["beam-timoshenko"]  # the beam theory alone, the same pad
    assert theory.previous == "beam" and dict(theory.options) == {"beam_theory": "timoshenko"}
    convention = rungs["beam-effective"]
    assert convention.previous == "beam" and convention.backend == "beam"
    assert dict(convention.options) == {"calibration": "effective"}
    for eng in ("mujoco", "bullet"):
        sdof, chain, full = (rungs[f"{eng}-sdof"], rungs[f"{eng}-chain7"],
                             rungs[f"{eng}-chain7-full"])
        assert sdof.previous == "soft" and chain.previous == "beam" and full.previous == chain.id
        # the engine's own pair differs in the trunk only
        assert dict(chain.options).keys() - dict(sdof.options).keys() == {"segments"}
        assert {k for k in dict(chain.options) if dict(chain.options)[k] != dict(
            sdof.options).get(k)} == {"trunk", "segments"}
        assert {k for k in dict(full.options) if dict(full.options)[k] != dict(
            chain.options)[k]} == {"pendulum"}
    rod = rungs["mujoco-flex7"]  # the engine's own elastic rod: the trunk alone vs the chain
    assert rod.kind == "rod" and rod.previous == "beam" and rod.level == 7
    assert {k for k in dict(rod.options) if dict(rod.options)[k] != dict(
        rungs["mujoco-chain7"].options)[k]} == {"trunk"}
    assert dict(rod.options)["trunk"] == "flex" and "bullet-flex7" not in rungs


def test_the_rod_rung_comes_from_the_registry_not_the_engine_name(monkeypatch):
    """An engine runs the ROD rung when its ``trunk`` option offers "flex", whatever its
    name: a test double offering it gets one, the same double without it gets none."""
    import sys
    import types

    from treeimpact.compare.runs.rungs import RungKind, rung_table

    def register(name, trunks):
        mod = types.ModuleType(f"_fake_{name}")
        mod.OPTIONS = {"trunk": Option(trunks, "trunk")}
        monkeypatch.setitem(sys.modules, mod.__name__, mod)
        monkeypatch.setitem(backends.BACKENDS, name, Backend(
            name, f"{mod.__name__}:simulate", None, "test double", engine=True))

    register("elastic", ("sdof", "chain", "flex"))
    register("stiff", ("sdof", "chain"))
    kinds = {r.id: r.kind for r in rung_table(("elastic", "stiff", "absent"), segments=5)}
    assert kinds["elastic-flex5"] == RungKind.ROD
    assert [k for k in kinds if kinds[k] == RungKind.ROD] == ["elastic-flex5"]
    letters = [k.letter for k in RungKind]
    assert RungKind.ROD.letter == "F" and len(set(letters)) == len(letters)


def test_default_segments_come_from_the_chain_convergence_rule():
    """The ladder's N is chain_segments' (the compared metrics' convergence on the exact
    chain and rod), never below the stiffness-and-frequency rule's; a given N is kept."""
    from treeimpact.analytic.continuum.chain import default_segments
    from treeimpact.compare.tree.ladder import chain_segments

    s = load_scenario("central-leader")
    n = chain_segments(s)
    assert n >= default_segments(s.trunk) and chain_segments(s, 7) == 7
    ids = [r.id for r in ladder_rungs("central-leader")]
    assert f"mujoco-chain{n}" in ids and f"bullet-chain{n}-full" in ids


def _fake_backend(monkeypatch, name, func):
    import sys
    import types

    mod = types.ModuleType(f"_fake_{name}")
    mod.simulate = func
    mod.OPTIONS = {"trunk": Option(("sdof", "chain"), "trunk")}
    monkeypatch.setitem(sys.modules, mod.__name__, mod)
    monkeypatch.setitem(backends.BACKENDS, name, Backend(name, f"{mod.__name__}:simulate",
                                                         None, "test double"))


def test_run_cache_records_skip_failure_and_divergence_with_reasons(monkeypatch):
    def crash(scenario, *, trunk="sdof"):
        raise RuntimeError("boom")

    def diverge(scenario, *, trunk="sdof"):
        raise SimulationDiverged("x went non-finite at t = 1 ms")

    _fake_backend(monkeypatch, "crash", crash)
    _fake_backend(monkeypatch, "diverge", diverge)
    cache = RunCache()
    absent = cache.run("open-center", "no-such-engine")
    assert absent.status == SKIPPED and "no-such-engine" in absent.reason
    option = cache.run("open-center", "crash", segments=3)  # an option it does not have
    assert option.status == SKIPPED and "--segments" in option.reason
    assert cache.run("open-center", "crash").status == FAILED
    assert cache.run("open-center", "crash").reason == "RuntimeError: boom"
    div = cache.run("open-center", "diverge")
    assert div.status == DIVERGED and "non-finite" in div.reason


def test_run_cache_runs_each_key_once():
    cache = RunCache()
    a = cache.run("open-center", "analytic", samples=11)
    b = cache.run(load_scenario("open-center"), "analytic", samples=11)
    c = cache.run("open-center", "analytic", samples=21)
    assert a is b and a is not c and a.status == OK
    assert len(cache) == 2 and cache.timings()["analytic"]["runs"] == 2


def test_ladder_keeps_unavailable_rungs_as_explicit_skips():
    ladder = build_ladder("open-center", cache=RunCache(), engines=("no-such-engine",),
                          segments=4)
    skipped = [r for r in ladder.rungs if not r.ok]
    assert [r.rung.id for r in skipped] == ["no-such-engine-sdof", "no-such-engine-chain4",
                                            "no-such-engine-chain4-full"]
    for r in skipped:
        assert r.status == SKIPPED and "no-such-engine" in r.reason
        assert all(math.isnan(v) for v in r.values.values())
        assert "rung not run" in r.identification.reason
    js = ladder.to_json()
    assert [r["status"] for r in js["rungs"]] == ["ok"] * 5 + ["skipped"] * 3
    # no check is made against a rung that did not run
    assert not {c.rung for c in ladder.checks()} & {r.rung.id for r in skipped}


def test_ladder_values_are_the_backends_metrics_and_steps_are_relative():
    cache = RunCache()
    ladder = build_ladder("central-leader", cache=cache, engines=())
    scen = load_scenario("central-leader")
    exact = simulate(scen)  # independent run, default sampling
    assert ladder.value("analytic", "V") == pytest.approx(exact.metrics["V"], rel=1e-12)
    soft = ladder["soft"].result.metrics
    assert ladder.step("soft", "x_max") == pytest.approx(
        (soft["x_max"] - exact.metrics["x_max"]) / exact.metrics["x_max"], rel=1e-9)
    assert set(ladder["analytic"].values) == set(ALL_METRICS)
    assert math.isnan(ladder.step("analytic", "V"))  # rung 1 has no step


def _check(value, ref, entry, metric="V", findings=(), physics=None):
    tol = {"finding": list(findings)}
    physics = TreePhysics(0.1, 12.0, 2.0) if physics is None else physics
    return judge("s", "r", "trunk", metric, value, "p", ref, entry, tol, physics)


def test_verdicts():
    entry = {"rel": 0.05, "reason": "why"}
    assert _check(1.04, 1.0, entry).verdict == "ok"
    assert _check(1.06, 1.0, entry).verdict == "exceeds"
    assert _check(-0.94, -1.0, entry).rel_diff == pytest.approx(0.06)
    assert _check(1.06, 1.0, {"report_only": True, "reason": "r"}).verdict == "reported"
    assert _check(math.nan, 1.0, entry, metric="x_max").verdict == "n/a"
    # a quantity the tree's motion does not have: skipped with the physical reason
    none = _check(math.nan, math.nan, entry, metric="x_max")
    assert none.verdict == "skipped" and "no value on r nor on p" in none.reason
    one = _check(math.nan, 1.0, entry)  # V on the reference only: different regimes
    assert one.verdict == "skipped" and "different regimes" in one.reason
    assert "move together" in _check(math.nan, math.nan, entry).reason
    f = {"name": "light clamp", "kinds": ["trunk"], "metric": "V",
         "when": {"loss_ratio_above": 2.0, "restitution_below": 0.5}, "band": [0.2, 0.5],
         "cause": "finding at loss_ratio {loss_ratio:g}", "reason": "the evidence"}
    assert _check(1.3, 1.0, entry, findings=[f]).verdict == "finding"
    assert _check(1.3, 1.0, entry, findings=[f]).reason == "finding at loss_ratio 12"
    assert _check(1.03, 1.0, entry, findings=[f]).verdict == "finding-lost"  # hidden
    assert _check(1.7, 1.0, entry, findings=[f]).verdict == "out-of-band"
    # the cause absent (a clamp as heavy as M_T; e above the rule's): judged as any step
    assert _check(1.3, 1.0, entry, findings=[f],
                  physics=TreePhysics(0.1, 1.5, 2.0)).verdict == "exceeds"
    assert _check(1.3, 1.0, entry, findings=[f],
                  physics=TreePhysics(0.6, 12.0, 2.0)).verdict == "exceeds"
    # no physics, no finding: a tree's name never selects one
    assert judge("s", "r", "trunk", "V", 1.3, "p", 1.0, entry,
                 {"finding": [f]}).verdict == "exceeds"


def test_every_tolerance_has_a_reason_and_bad_files_are_refused(tmp_path):
    for section in ("step", "engines"):
        for kind, metrics in TOL.get(section, {}).items():
            for metric, entry in metrics.items():
                assert metric in ALL_METRICS, f"{section}.{kind}.{metric}: unknown metric"
                assert len(entry["reason"]) > 20
    # a fixed band, or one derived per tree (compare.runs.bounds.continuum)
    for f in TOL["finding"]:
        assert f["metric"] in ALL_METRICS
        assert f["band"][0] < f["band"][1] if "band" in f else f["band_bound"]
    bad = tmp_path / "t.toml"
    bad.write_text('[step.engine]\nV = { rel = 0.01 }\n')
    with pytest.raises(ParameterError, match="reason"):
        load_tolerances(bad)
    bad.write_text('[step.engine]\nV = { reason = "no number" }\n')
    with pytest.raises(ParameterError, match="rel, bound or report_only"):
        load_tolerances(bad)
    for name, entry in TOL.get("identification_refused", {}).items():
        assert name not in shipped_scenarios() and len(entry["reason"]) > 20, name
        assert entry["when"], name  # expected under a physical condition, not for a tree
    for f in TOL["finding"]:
        assert "scenario" not in f and f["when"], f["name"]
    head = '[identification_reported]\nreason = "reported"\n'
    bad.write_text(head + '[[finding]]\nname = "n"\nscenario = "open-center"\nkinds = ["beam"]\n'
                   'metric = "x_max"\nwhen = {}\nband = [0.1, 0.2]\ncause = "c"\nreason = "r"\n')
    with pytest.raises(ParameterError, match="never from a tree's name"):
        load_tolerances(bad)
    bad.write_text(head + '[[finding]]\nname = "n"\nkinds = ["beam"]\nmetric = "x_max"\n'
                   'when = { tree_above = 1 }\nband = [0.1, 0.2]\ncause = "c"\nreason = "r"\n')
    with pytest.raises(ParameterError, match="quantities"):
        load_tolerances(bad)
    bad.write_text(head + '[[finding]]\nname = "n"\nkinds = ["beam"]\nmetric = "x_max"\n'
                   'when = {}\nband = [0.1, 0.2]\nreason = "r"\n')
    with pytest.raises(ParameterError, match="cause: missing"):
        load_tolerances(bad)
    bad.write_text(head + '[[finding]]\nname = "n"\nkinds = ["beam"]\nmetric = "x_max"\n'
                   'when = {}\nband = [0.1, 0.2]\ncause = "at {x_max_shipped}"\nreason = "r"\n')
    with pytest.raises(ParameterError, match="not a tree's quantity"):
        load_tolerances(bad)
    finding = head + '[[finding]]\nname = "n"\nkinds = ["beam"]\nmetric = "x_max"\n' \
        'when = {}\ncause = "c"\nreason = "r"\n'
    for band, match in (('band = [0.1, 0.2]\nband_bound = "mesh"\n', "band or band_bound"),
                        ("", "band or band_bound"), ('band_bound = "fitted"\n', "allowed"),
                        ('band_bound = "mesh"\n', "mesh_rel")):
        bad.write_text(finding + band)
        with pytest.raises(ParameterError, match=match):
            load_tolerances(bad)
    bad.write_text('[identification_reported]\nreason = "reported"\n[identification_refused]\n'
                   'x = { match = "refused", reason = "a refusal without its words" }\n')
    with pytest.raises(ParameterError, match="not identifiable"):
        load_tolerances(bad)


@pytest.mark.parametrize("name", ["open-center", "central-leader", "realistic-crown"])
def test_identification_tolerances_are_the_procedure_floor_at_e0(name):
    """The [identification] tolerances are the procedure's own error on the exact e = 0
    record (the paper's assumption). Measured here again: M_T, K_T, E within them for every
    shipped scenario (pair_damping_ratio for the light crowns), so the e = 0.1 findings are caused by e."""
    scen = load_scenario(name)
    res = simulate(scenario_as_run(scen, {"restitution": 0.0}),
                   samples=int(round(scen.t_end / ANALYTIC_SAMPLE_STEP))
                   + 1)
    tr = res.trajectory
    ident, _ = identify_from_record(tr.t, tr.x, pendulum_test_of(scen), y=tr.y, reading="paper")
    err = identification_errors(ident, truth_of(scen))
    keys = IDENT_METRICS if name != "realistic-crown" else ("M_T", "K_T", "E")
    # a per-tree bound (pair_damping_ratio: procedure-floor) is this floor at the record's
    # window: test_bounds_contact.py checks it
    for k in (k for k in keys if "rel" in TOL["identification"][k]):
        assert abs(err[k]) <= TOL["identification"][k]["rel"], (k, err[k])
    # the floor is not slack: M_T's tolerance is within a factor 2 of the measured floor
    assert abs(err["M_T"]) > TOL["identification"]["M_T"]["rel"] / 2


def test_failure_table_names_metric_values_difference_tolerance_and_reason():
    ladder = build_ladder("open-center", cache=RunCache(), engines=())
    entry = {"rel": 1e-6, "reason": "a deliberately tiny tolerance"}
    c = judge("open-center", "soft", "contact", "x_max", ladder.value("soft", "x_max"),
              "analytic", ladder.value("analytic", "x_max"), entry, TOL, ladder.physics)
    assert c.verdict == "exceeds"
    text = failure_table(ladder, [c])
    lines = text.splitlines()
    assert lines[1].split()[:4] == ["metric", "unit", "analytic", "soft"]
    row = lines[2]
    assert row.startswith("x_max") and " m " in row
    assert f"{ladder.value('soft', 'x_max'):.5g}" in row
    assert f"{c.rel_diff:+.3%}" in row and "1e-06" in row and "deliberately tiny" in row


@pytest.mark.parametrize("scenario, ambiguous", [("central-leader", True),
                                                 ("realistic-crown", True),
                                                 ("open-center", False)])
def test_peak_time_of_two_near_equal_maxima_is_flagged_not_judged(ladder_of, scenario,
                                                                  ambiguous):
    """The continuum trunk's x(t) has a second maximum within 5 % of the largest
    (central-leader: 12.0 and 16.8 ms, 1.8 % apart; realistic-crown: 26.7 and 32.1 ms, 0.8 %):
    its t_xmax against the SDOF's single peak is 'ambiguous'; open-center's continuum has one
    clear peak and its t_xmax step stays a judged finding."""
    ladder = ladder_of(scenario)
    chain = next(r for r in ladder.rungs if r.rung.kind == "beam" and r.ok)
    check = ladder.step_check(chain.rung.id, "t_xmax")
    if ambiguous:
        assert len(chain.peaks) == 2 and check.verdict == "ambiguous"
        assert "maxima within 5 % of each other" in check.reason
    else:
        assert len(chain.peaks) == 1 and check.verdict == "finding"
    assert ladder.step_check(chain.rung.id, "x_max").verdict == "finding"  # x_max is robust


def test_every_engine_run_says_its_steps_and_what_set_its_step(ladder_of, run_cache):
    """The ladder's engine runs carry their stepping (steps, wall per step, what set dt) into
    report.json's run list and the page's; the analytic backends, which do not step, none.
    The report's chains (10-12 segments) are stepped by their contact, not the chain's
    highest mode (docs/time-step.md); a chain run stepped by phase covers t_end with its
    contact steps and its free steps (docs/engines.md "Stepping by phase")."""
    from treeimpact.compare.report.runlog import run_rows
    from treeimpact.compare.runs.backends import ENGINES

    ladder_of("open-center")
    runs = [r for r in run_cache if r.ok]
    engine_runs = [r for r in runs if r.backend in ENGINES]
    assert engine_runs and all(r.backend in ENGINES for r in runs if r.stepping)
    for r in engine_runs:
        js = r.to_json()["stepping"]
        free = js.get("free_steps", 0)
        covered = (js["steps"] - free) * js["dt"] + free * (js.get("free_dt") or 0.0)
        assert covered >= r.result.scenario["t_end"] - js["dt"] and js["step_us"] > 0
        # the session's cache also holds other tests' runs with a dt of their own
        expected = ("given",) if "dt" in r.options else ("contact", "implicit contact")
        assert js["step_set_by"] in expected, r.describe()
    rows = run_rows(engine_runs)
    assert all(row["stepping"]["steps"] > 0 for row in rows)


def test_two_records_whose_largest_maximum_is_another_peak_are_ambiguous():
    """Both records with near-equal maxima (times a, b): the time of the maximum is judged
    only where both pick the same peak (the family's high clamp: four maxima within 1.1 %,
    the chain's largest the beam's second); a single-peaked record is left to the rule of
    one against several."""
    from treeimpact.compare.runs.peaks import other_peak as _other_peak

    a, b = [0.010, 0.030], [0.011, 0.031]
    assert _other_peak(a, b, 0.010, 0.031) and _other_peak(b, a, 0.031, 0.010)
    assert not _other_peak(a, b, 0.010, 0.011) and not _other_peak(a, b, 0.030, 0.031)
    assert not _other_peak([0.010], b, 0.010, 0.031)  # one peak: the other rule's case
    assert not _other_peak(a, b, math.nan, 0.031)


def test_a_flat_top_within_the_x_max_tolerance_resolves_no_time_of_the_maximum():
    """x(t) = 1 - (t - 0.02)^2 / 0.01^2 near its top: at 0.021 s it is 1 % below its
    maximum, so within a 1.5 % x_max tolerance and not within 0.5 %; outside the record or
    at a NaN time nothing is within."""
    from types import SimpleNamespace

    import numpy as np

    from treeimpact.compare.runs.peaks import within_top

    t = np.linspace(0.0, 0.04, 4001)
    rec = SimpleNamespace(t=t, x=1.0 - (t - 0.02) ** 2 / 0.01 ** 2)
    assert within_top(rec, 0.021, 0.015) and not within_top(rec, 0.021, 0.005)
    assert not within_top(rec, 0.05, 0.5) and not within_top(rec, math.nan, 0.5)
