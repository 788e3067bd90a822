"""A study that survives its points (issue 50 item 4): each input's range valid for the tree
it is applied to (compare.studies.input_ranges), a point that cannot run kept with its
index, inputs and reason (compare.studies.study_points), the Morris and Sobol indices on
the complete trajectories and Saltelli blocks only, the count on the page and in the JSON,
exit 0 with a stderr line when some points failed and exit 4 when none ran."""

from __future__ import annotations

import itertools
import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.studies import sensitivity as S
from treeimpact.compare.studies.input_ranges import registry_range
from treeimpact.compare.studies.sobol import analyse_sobol, sobol_design


def _light_tree():
    """open-center with a 0.5 kg crown: M_T so near its bare trunk's that the densest
    wood with the heaviest clamp of the registry's ranges leaves a crown of negative mass."""
    s = load_scenario("open-center")
    return replace(s, name="light", trunk=replace(s.trunk, crown_mass=0.5))


def _corners(ranges, names):
    return [dict(zip(names, c)) for c in itertools.product(
        *[(ranges[n]["low"], ranges[n]["high"]) for n in names])]


def test_each_range_is_valid_for_the_tree_it_is_applied_to():
    """On the light tree the registry's box holds corners the calibration refuses (crown
    m_f < 0, eq 7); the tree's ranges narrow the density and the clamp mass, say why, and
    every corner of the narrowed box (root share at its ends and middle) is a tree."""
    scen = _light_tree()
    own = S.inputs_of(scen)
    ranges = S.ranges_of(scen)
    names = ("clamp_mass", "density", "root_share")
    registry = {n: dict(zip(("low", "high"), registry_range(n))) for n in names}
    refused = 0
    for corner in _corners(registry, names):
        try:
            S.vary(scen, own | corner)
        except ParameterError as exc:
            assert "below the bare trunk" in str(exc)
            refused += 1
    assert refused > 0  # the registry's box is not valid for this tree
    for n in ("clamp_mass", "density"):
        assert ranges[n]["high"] < registry[n]["high"] and "M_T" in ranges[n]["clipped"]
        assert ranges[n]["low"] == registry[n]["low"]
    share = ranges["root_share"]
    for corner in _corners(ranges, ("clamp_mass", "density")):
        for s in np.linspace(share["low"], share["high"], 5):
            varied, _ = S.vary(scen, own | corner | {"root_share": float(s)})
            assert varied.trunk.crown_mass >= 0.0
    # the shipped trees keep the registry's ranges
    assert not any(v["clipped"] for v in S.ranges_of(load_scenario("open-center")).values())


@pytest.mark.parametrize("trunk, clipped, refused", [
    ({"youngs_modulus": 9e10, "base_stiffness": 1e9}, "root_share",
     "trunk.youngs_modulus = "),  # rule 1: a stiff trunk on a near-rigid root
    ({"youngs_modulus": 1.5e7}, "e_over_g", "trunk.shear_modulus = "),  # rule 2: soft wood
])
def test_the_modulus_rules_narrow_the_range_the_trunk_would_refuse(trunk, clipped, refused):
    """A tree whose registry corner (root share, E/G at their far ends) the trunk's own
    checks refuse: the tree's range of that input is narrowed with its rule, and the corners
    of the narrowed root share x E/G box are trees."""
    s = load_scenario("open-center")
    scen = replace(s, name="edge", trunk=replace(s.trunk, **trunk))
    own = S.inputs_of(scen)
    ranges = S.ranges_of(scen)
    names = ("root_share", "e_over_g")
    registry = {n: dict(zip(("low", "high"), registry_range(n))) for n in names}
    messages = []
    for corner in _corners(registry, names):
        try:
            S.vary(scen, own | corner)
        except ParameterError as exc:
            messages.append(str(exc))
    assert messages and all(m.startswith(refused) for m in messages)
    assert ranges[clipped]["high"] < registry[clipped]["high"] and ranges[clipped]["clipped"]
    for corner in _corners(ranges, names):
        S.vary(scen, own | corner)  # raises if a corner is no tree


def _linear(x: dict) -> float:
    """A gap linear in two inputs: Morris mu* = |c| (high - low) exactly on any trajectory,
    Sobol S1 = ST = c^2 var / total (independent uniforms)."""
    return 2.0 * x["root_share"] + 0.5 * x["restitution"]


def _table(X, names, fail):
    rows = []
    for i, x in enumerate(X):
        p = dict(zip(names, x))
        row = {"status": "ok", **{f"input.{k}": v for k, v in p.items()}}
        if i in fail:
            row |= {"status": "invalid", "error": "dynamic_mass = 1 kg: below the bare trunk"}
        else:
            row |= {f"gap.{m}": _linear(p) for m in S.ANSWER}
        rows.append(row)
    return pd.DataFrame(rows)


def test_morris_drops_a_trajectory_with_a_failed_point_and_says_so(tmp_path):
    """4 trajectories, points 8 and 9 (the second trajectory) failed: the indices rest on 3,
    mu* is exactly |c| (high - low) (a partial trajectory would break it), and each failed
    point is named with its index, inputs (registry names and units) and reason."""
    names = list(S.INPUTS)
    X = S.design(4)
    table = _table(X, names, {8, 9})
    table.loc[20, "gap.x_max"] = float("nan")  # ran, without this one number
    out = S.analyse(table, 4)
    assert out["failed"] == 2 and out["trajectories_used"] == 3 and out["points"] == 28
    assert out["evaluations"] == 26
    x = out["outputs"]["gap.x_max"]
    assert x["basis"] == {"trajectories": 2, "of": 4, "points": 14, "non_finite": 1}
    assert x["evaluations"] == 25
    assert out["outputs"]["gap.energy_delivered"]["basis"] == {
        "trajectories": 3, "of": 4, "points": 21, "non_finite": 0}
    table["gap.peak_force"] = float("nan")  # no point has it: the output is refused, said
    gone = S.analyse(table, 4)
    assert "gap.peak_force" not in gone["outputs"]
    assert gone["refused"]["gap.peak_force"].startswith("no complete trajectory has a finite")
    from treeimpact.compare.report.validity.sensitivity_study import said
    from treeimpact.compare.report.validity.study import write_study

    said(gone)
    paths = write_study(tmp_path, {}, sensitivity={"trajectories": 4, "crossings": False,
                                                   "sobol": 0, "trees": {"t": gone},
                                                   "figure": None})
    page = paths["md"].read_text()
    assert "- t, force gap: no indices, no complete trajectory has a finite" in page
    assert x["indices"]["root_share"]["mu_star"] == pytest.approx(2.0 * 0.9, rel=1e-12)
    assert x["indices"]["restitution"]["mu_star"] == pytest.approx(0.5 * 0.45, rel=1e-12)
    assert x["indices"]["density"]["mu_star"] == pytest.approx(0.0, abs=1e-12)
    first = out["failed_points"][0]
    assert first["index"] == 8 and first["status"] == "invalid"
    assert first["inputs"]["density"] == {"value": X[8][names.index("density")],
                                          "unit": "kg/m^3"}
    assert first["text"].startswith("point 8 (clamp_mass = ")
    assert first["text"].endswith("kg/m^3): dynamic_mass = 1 kg: below the bare trunk")


def test_sobol_indices_rest_on_the_complete_blocks():
    """N = 256, one point failed in each of 32 blocks: the indices come from the 224
    complete blocks, S1 and ST of the linear gap within their own 95 % intervals of the
    closed form (Saltelli's estimator on complete blocks is unbiased), the basis said."""
    n, names = 256, list(S.INPUTS)
    X = sobol_design(n)
    size = len(names) + 2
    fail = {b * size + (b % size) for b in range(0, n, 8)}
    out = analyse_sobol(_table(X, names, fail), n)
    assert out["failed"] == 32 and out["blocks_used"] == 224
    entry = out["outputs"]["gap.x_max"]
    assert entry["basis"] == {"blocks": 224, "of": n, "points": 224 * size, "non_finite": 0}
    var = {"root_share": (2.0 * 0.9) ** 2 / 12, "restitution": (0.5 * 0.45) ** 2 / 12}
    total = sum(var.values())
    for name, v in var.items():
        got = entry["indices"][name]
        for k in ("S1", "ST"):
            assert abs(got[k] - v / total) <= got[f"{k}_conf"], (name, k, got[k])


def _flaky(bad):
    """answer_under, refusing the points for which ``bad(params)`` holds as a point that
    makes no valid tree would be refused."""
    real = S.answer_under

    def run(result, scenario, params):
        if bad(params):
            raise ParameterError(f"dynamic_mass: no tree at restitution = "
                                 f"{params['restitution']:.6g}")
        return real(result, scenario, params)

    run.columns = real.columns
    return run


def test_a_study_survives_a_point_that_cannot_run(tmp_path, monkeypatch):
    """Morris (2 trajectories) and Sobol (N = 2) on open-center with every point above
    e = 0.3 refused: the study completes, counts and names the failed points with their
    inputs, the indices say what they rest on, the page (html and md) shows the count and
    stderr's line says it."""
    from treeimpact.compare.report.validity.sensitivity_study import run_sensitivity
    from treeimpact.compare.report.validity.study import _points_said, write_study

    monkeypatch.setattr(S, "answer_under", _flaky(lambda p: p["restitution"] > 0.3))
    study = tmp_path / "study"
    sens = run_sensitivity(study, 2, scenarios=["open-center"], workers=0, sobol=2,
                           progress=False)
    tree = sens["trees"]["open-center"]
    X = S.design(2)
    bad = [i for i, x in enumerate(X) if x[list(S.INPUTS).index("restitution")] > 0.3]
    assert bad and tree["failed"] == len(bad) and tree["points"] == len(X)
    assert [f["index"] for f in tree["failed_points"]] == bad
    assert tree["failed_points"][0]["reason"].startswith("dynamic_mass: no tree at")
    assert tree["trajectories_used"] == 2 - len({i // 7 for i in bad})
    assert tree["points_text"].startswith(f"{len(bad)} of 14 points failed; ")
    sb = tree["sobol"]
    assert sb["failed"] + sb["evaluations"] == sb["points"] == 16
    paths = write_study(study, {}, sensitivity=sens)
    data = json.loads(paths["json"].read_text())["sensitivity"]["trees"]["open-center"]
    assert data["failed_points"][0]["inputs"]["restitution"]["unit"] == "1"
    for page in ("html", "md"):
        text = paths[page].read_text()
        assert f"{len(bad)} of 14 points failed" in text
        assert f"point {bad[0]} (clamp_mass = " in text
    said = _points_said(paths, sens, study)["warnings"]
    assert said[0].startswith(f"sensitivity open-center (Morris): {len(bad)} of 14 points "
                              "failed; ")
    assert f"The first: point {bad[0]} (clamp_mass = " in said[0]


def _tiny(monkeypatch):
    """A preset of a one-point validity sweep and a one-trajectory Morris, N = 1 Sobol
    sensitivity part (15 points on open-center), registered for this test."""
    from treeimpact.compare.report.validity.presets import PRESETS, Preset

    monkeypatch.setitem(PRESETS, "tiny", Preset(
        "tiny", "open-center", ("restitution=0.1",), ladder=False, engines=(), speed=False,
        backends=("analytic",), sensitivity=1, sobol=1))
    return ["sweep", "--preset", "tiny", "--workers", "0", "--sensitivity-scenario",
            "open-center"]


def test_a_study_where_no_point_ran_exits_4_with_one_line(tmp_path, monkeypatch, capsys):
    """Every point refused: ``treeimpact sweep --preset`` writes the study and exits 4 with
    one stderr line naming the first point and its inputs."""
    from treeimpact.compare.interface.cli import main

    monkeypatch.setattr(S, "answer_under", _flaky(lambda p: True))
    out = tmp_path / "study"
    code = main([*_tiny(monkeypatch), "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 4, err
    assert len(err) == 1 and err[0].startswith("treeimpact: not achieved: sensitivity: "
                                               "none of its 15 points ran")
    assert "the first: point 0 (clamp_mass = " in err[0]
    assert (out / "study.html").is_file()


def test_a_study_with_some_failed_points_exits_0_and_says_so(tmp_path, monkeypatch, capsys):
    """Points above e = 0.3 refused: exit 0, and stderr's warning per design with a failed
    point says how many and names the first."""
    from treeimpact.compare.interface.cli import main

    monkeypatch.setattr(S, "answer_under", _flaky(lambda p: p["restitution"] > 0.3))
    code = main([*_tiny(monkeypatch), "--out", str(tmp_path / "study")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 0, err
    data = json.loads((tmp_path / "study" / "study.json").read_text())
    tree = data["sensitivity"]["trees"]["open-center"]
    designs = [d for d in (tree, tree["sobol"]) if d["failed"]]
    assert 0 < tree["failed"] + tree["sobol"]["failed"] < 15
    assert len(err) == len(designs)
    assert all(e.startswith("treeimpact: warning: sensitivity open-center (") for e in err)
    assert all(" points failed; " in e and " The first: point " in e for e in err)


def test_a_report_says_not_achieved_when_its_study_exits_4(tmp_path):
    """The report's study job (a child process) ending with exit 4 is the report's
    NotAchieved (exit 4), not a bad input, with the child's last line."""
    import sys

    from treeimpact.analytic.errors import NotAchieved
    from treeimpact.compare.report.validity.study_job import StudyJob

    child = [sys.executable, "-c", "import sys; print('treeimpact: not achieved: "
             "sensitivity: none of its 3 points ran'); sys.exit(4)"]
    job = StudyJob("default", tmp_path / "study", child).start()
    with pytest.raises(NotAchieved, match="exit code 4: treeimpact: not achieved: "
                                          "sensitivity: none of its 3 points ran"):
        job.result()
