"""The answer with error bars (compare.sensitivity): the unmeasured inputs varied on the
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
from treeimpact.compare.sensitivity import (
    ANSWER,
    INPUTS,
    analyse,
    answer_under,
    design,
    sensitivity_sweep,
    vary,
)

#: The shipped trees' own choices of the unmeasured inputs (scenario files).
SHIPPED = {"clamp_mass": 4.0, "e_over_g": 0.0, "log10_pad_duration": math.log10(5e-4),
           "restitution": 0.1, "root_share": None, "density": 950.0}


def _shipped(name):
    scen = load_scenario(name)
    t = scen.trunk
    bending = t.clamp_height ** 3 / (3.0 * t.bending_stiffness)  # m/N
    return scen, SHIPPED | {"root_share": 1.0 - bending * reduce_trunk(t).stiffness}


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
        for f in ("dynamic_mass", "stiffness", "damping"):
            assert getattr(got, f) == pytest.approx(getattr(ref, f), rel=1e-9), f


def test_the_design_is_reproducible_and_morris_shaped():
    a, b = design(3), design(3)
    assert a.shape == (3 * (len(INPUTS) + 1), len(INPUTS)) and np.array_equal(a, b)
    lows = np.array([v[0] for v in INPUTS.values()])
    highs = np.array([v[1] for v in INPUTS.values()])
    assert np.all(a >= lows - 1e-12) and np.all(a <= highs + 1e-12)


def test_analyse_names_the_input_that_moves_an_output():
    """A synthetic table where the x_max gap depends on the clamp mass alone and the
    energy gap on e: Morris ranks them first, the ranges are the outputs' own."""
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
    assert out["outputs"]["gap.x_max"]["dominant"] == "clamp_mass"
    assert out["outputs"]["gap.energy_delivered"]["dominant"] == "restitution"
    assert out["outputs"]["gap.x_max"]["low"] == pytest.approx(0.01)
    assert out["outputs"]["gap.x_max"]["high"] == pytest.approx(0.16)
    mu = out["outputs"]["gap.x_max"]["mu_star"]
    assert mu["clamp_mass"] > 0 and all(v == 0 for k, v in mu.items() if k != "clamp_mass")


def test_the_study_of_one_tree_runs_on_the_sweeps(tmp_path):
    """One Morris trajectory (7 points) as a sweep, in this process: every point finite."""
    from treeimpact.compare.sweep.run import run_sweeps

    (res,) = run_sweeps([sensitivity_sweep("open-center", tmp_path, 1)], workers=0,
                        progress=False)
    assert len(res.table) == len(INPUTS) + 1 and set(res.table["status"]) == {"ok"}
    out = analyse(res.table, 1)
    assert set(out["outputs"]) == {f"gap.{m}" for m in ANSWER}
    assert all(math.isfinite(o["low"]) and o["low"] <= o["high"]
               for o in out["outputs"].values())
