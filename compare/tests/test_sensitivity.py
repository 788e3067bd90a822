"""The answer with error bars (compare.studies.sensitivity): the unmeasured inputs varied on the
same measured tree, the Morris design and its reading."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.studies.sensitivity import (
    ANSWER,
    analyse,
    answer_under,
    deciding,
    design,
    sensitivity_sweep,
)
from treeimpact.compare.studies.study_inputs import (
    INPUTS,
    free_inputs,
    inputs_of,
    measured_inputs,
    vary,
)

#: The shipped trees' own choices of the unmeasured inputs (scenario files).
SHIPPED = {"clamp_mass": 4.0, "e_over_g": 0.0, "log10_pad_duration": math.log10(5e-4),
           "restitution": 0.1, "root_share": None, "density": 950.0}


def _shipped(name):
    scen = load_scenario(name)
    t = scen.trunk
    bending = t.clamp_height ** 3 / (3.0 * t.bending_stiffness)  # m/N
    return scen, SHIPPED | {"root_share": 1.0 - bending * reduce_trunk(t).equivalent_stiffness}


@pytest.mark.parametrize("name", ["open-center", "central-leader", "realistic-crown"])
def test_a_trees_own_inputs_are_read_from_its_file(name):
    """inputs_of gives the files' values (root share from E I and K_T, eq 8; 1e-12)."""
    scen, p = _shipped(name)
    got = inputs_of(scen)
    assert set(got) == set(INPUTS)
    for k, v in p.items():
        assert got[k] == pytest.approx(v, rel=1e-12, abs=1e-15), k


@pytest.mark.parametrize("name", ["open-center", "realistic-crown"])
def test_the_shipped_inputs_give_back_the_shipped_tree_and_its_answer(name):
    """vary() at the shipped trees' own choices rebuilds them (crown, root spring, damping to
    1e-9) and answer_under gives the answer table's gaps of direct runs (1e-7: the same
    runs; the calibration's 1e-9 round trip moves the chattering contact's x_max by 3e-9)."""
    scen, p = _shipped(name)
    varied, theory = vary(scen, p)
    assert theory == "euler-bernoulli"
    for f in ("crown_mass", "base_stiffness", "damping", "youngs_modulus"):
        assert getattr(varied.trunk, f) == pytest.approx(getattr(scen.trunk, f), rel=1e-9), f
    got = answer_under(None, scen, p)
    newton, soft, beam = simulate(scen).metrics, simulate_soft(scen).metrics, \
        simulate_beam(scen).metrics
    for m in ANSWER:
        ref = newton[m] if math.isfinite(newton[m]) else soft[m]
        assert got[f"gap.{m}"] == pytest.approx((beam[m] - ref) / abs(ref), rel=1e-7), m


def test_every_point_of_the_design_keeps_the_measured_tree():
    """At the design's corners of every input the reduced M_T, K_T and C_T are Table 1's
    (the inputs move how the continuum carries them, not what was measured)."""
    scen = load_scenario("central-leader")
    ref = reduce_trunk(scen.trunk)
    for row in design(2):
        varied, _ = vary(scen, dict(zip(INPUTS, row)))
        got = reduce_trunk(varied.trunk)
        for f in ("dynamic_mass", "equivalent_stiffness", "equivalent_damping"):
            assert getattr(got, f) == pytest.approx(getattr(ref, f), rel=1e-9), f


def test_the_design_is_reproducible_and_morris_shaped():
    a, b = design(3), design(3)
    assert a.shape == (3 * (len(INPUTS) + 1), len(INPUTS)) and np.array_equal(a, b)
    lows = np.array([v[0] for v in INPUTS.values()])
    highs = np.array([v[1] for v in INPUTS.values()])
    assert np.all(a >= lows - 1e-12) and np.all(a <= highs + 1e-12)


def test_analyse_names_the_input_that_moves_an_output():
    """A synthetic table where the x_max gap depends on the clamp mass alone and the
    energy gap on e: Morris names each alone (its interval above every other's, which are
    0), the ranges are the outputs' own, SALib's keys kept beside each index."""
    X = design(4)
    rows = []
    for x in X:
        p = dict(zip(INPUTS, x))
        rows.append({"status": "ok", **{f"input.{n}": v for n, v in p.items()},
                     "gap.x_max": 0.01 * p["clamp_mass"],
                     "gap.energy_delivered": 2.0 * p["restitution"] ** 2,
                     **{f"gap.{m}": 0.1 * p["density"] / 1000 for m in ANSWER[2:]}})
    out = analyse(pd.DataFrame(rows), 4)
    assert out["failed"] == 0
    x = out["outputs"]["gap.x_max"]
    assert x["deciding"] == ["clamp_mass"] and x["separated"]
    assert out["outputs"]["gap.energy_delivered"]["deciding"] == ["restitution"]
    assert x["low"] == pytest.approx(0.01) and x["high"] == pytest.approx(0.16)
    assert x["evaluations"] == len(X)
    idx = x["indices"]
    assert set(idx["clamp_mass"]) == {"mu", "mu_star", "sigma", "mu_star_conf"}
    # linear in the clamp mass: SALib's elementary effect is the change per unit of the
    # input's normalised range, so mu* is 0.01 per kg times the 15 kg range
    span = INPUTS["clamp_mass"][1] - INPUTS["clamp_mass"][0]
    assert idx["clamp_mass"]["mu_star"] == pytest.approx(0.01 * span)
    assert idx["clamp_mass"]["mu_star_conf"] == pytest.approx(0.0, abs=1e-12)
    assert all(v["mu_star"] == 0 for k, v in idx.items() if k != "clamp_mass")


def test_an_input_is_named_alone_only_when_its_interval_clears_the_runner_up():
    """deciding(): the top mu* alone when mu* - conf lies above every other mu* + conf;
    else the inputs whose intervals reach into its; nothing when no input moves it."""
    def idx(**kw):
        return {k: {"mu_star": m, "mu_star_conf": c} for k, (m, c) in kw.items()}

    assert deciding(idx(a=(0.5, 0.05), b=(0.3, 0.1), c=(0.1, 0.01))) == (["a"], True)
    assert deciding(idx(a=(0.50, 0.09), b=(0.46, 0.08), c=(0.28, 0.08))) == (
        ["a", "b"], False)
    assert deciding(idx(a=(0.50, 0.2), b=(0.46, 0.08), c=(0.28, 0.08))) == (
        ["a", "b", "c"], False)
    assert deciding(idx(a=(0.0, 0.0), b=(0.0, 0.0))) == ([], False)


def test_the_study_of_one_tree_runs_on_the_sweeps(tmp_path):
    """One Morris trajectory (7 points) as a sweep, in this process: every point finite."""
    from treeimpact.compare.studies.sweep.run import run_sweeps

    (res,) = run_sweeps([sensitivity_sweep("open-center", tmp_path, 1)], workers=0,
                        progress=False)
    assert len(res.table) == len(INPUTS) + 1 and set(res.table["status"]) == {"ok"}
    out = analyse(res.table, 1)
    assert set(out["outputs"]) == {f"gap.{m}" for m in ANSWER}
    assert all(o["convergence"] is None for o in out["outputs"].values())  # < 4 trajectories
    assert all(math.isfinite(o["low"]) and o["low"] <= o["high"]
               for o in out["outputs"].values())


def _measured(tmp_path, scenario, fields):
    """The scenario as a file whose [calibration] says ``fields`` were measured."""
    from treeimpact.analytic.model.scenario_toml import scenario_toml

    text = scenario_toml(scenario).replace(
        "[calibration]", "[calibration]\nmeasured = [" + ", ".join(f'"{f}"' for f in fields)
        + "]")
    path = tmp_path / f"{scenario.name}.toml"
    path.write_text(text)
    return load_scenario(path)


def test_a_measured_input_is_held_at_the_files_value(tmp_path):
    """[calibration] measured = [trunk.base_stiffness, contact.restitution]: the design
    varies the four others; every point is the tree with its root spring and e (1e-9)."""
    scen = _measured(tmp_path, load_scenario("central-leader"),
                     ["trunk.base_stiffness", "contact.restitution"])
    assert measured_inputs(scen) == ("restitution", "root_share")
    names = free_inputs(scen)
    assert names == ("clamp_mass", "e_over_g", "log10_pad_duration", "density")
    spec = sensitivity_sweep(scen, tmp_path / "sweep", 2)
    assert spec.grid.names == tuple(f"input.{n}" for n in names)
    own = inputs_of(scen)
    for row in spec.grid.design:
        varied, _ = vary(scen, own | dict(zip(names, row)))
        assert varied.contact.restitution == scen.contact.restitution
        assert varied.trunk.youngs_modulus == pytest.approx(scen.trunk.youngs_modulus,
                                                            rel=1e-9)


def test_measuring_the_deciding_input_narrows_its_band(tmp_path):
    """central-leader's x_max gap is decided by the root's compliance (with the shear and
    the pad, not separable at 6 trajectories); measuring the root (the file's base
    stiffness held) narrows the band the answer table prints to under two thirds."""
    from treeimpact.compare.studies.sweep.run import run_sweeps

    scen = load_scenario("central-leader")
    held = _measured(tmp_path, scen, ["trunk.base_stiffness"])
    bands = {}
    for label, s in (("free", scen), ("held", held)):
        (res,) = run_sweeps([sensitivity_sweep(s, tmp_path / label, 6)], workers=0,
                            progress=False)
        out = analyse(res.table, 6, names=free_inputs(s))
        x = out["outputs"]["gap.x_max"]
        bands[label] = x["high"] - x["low"]
        if label == "free":
            assert "root_share" in x["deciding"]
    assert bands["held"] < 2 / 3 * bands["free"]
