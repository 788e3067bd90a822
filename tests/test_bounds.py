"""The per-tree bound mechanism (compare.runs.bounds): an entry naming a bound gets that tree's
tolerance and words; a bound that is not registered, or given beside a fixed rel, is
refused in one line."""

from __future__ import annotations

import math
import re
from types import SimpleNamespace

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.runs import bounds as B


def _pair(value, reference):
    run = lambda v: SimpleNamespace(values={"x_max": v}, result=None)  # noqa: E731
    return B.Pair(None, None, "x_max", run(value), run(reference))


def test_a_named_bound_sets_the_tree_s_tolerance_and_says_how():
    name = "test-half-the-reference"
    B.BOUNDS.pop(name, None)
    B.register(name)(lambda p: B.Bound(0.5 * p.reference_value, "half of it"))
    try:
        entry = B.tree_entry({"bound": name, "reason": "because"}, _pair(1.0, 0.02))
    finally:
        B.BOUNDS.pop(name)
    assert math.isclose(entry["rel"], 0.01) and entry["reason"] == "because: half of it"


def test_an_entry_without_a_bound_is_unchanged():
    entry = {"rel": 0.005, "reason": "r"}
    assert B.tree_entry(entry, _pair(1.0, 1.0)) is entry and B.tree_entry(None, None) is None


@pytest.mark.parametrize("entry, words", [
    ({"bound": "no-such-bound", "reason": "r"}, "bound = 'no-such-bound': allowed"),
    ({"bound": next(iter(B.BOUNDS), "x"), "rel": 0.1, "reason": "r"}, "not both")])
def test_a_bad_bound_is_refused_in_one_line(entry, words):
    if entry["bound"] not in B.BOUNDS and "rel" in entry:
        pytest.skip("no bound registered yet")
    with pytest.raises(ParameterError, match=words):
        B.validate_bound("step.x.x_max", entry)


@pytest.mark.parametrize("floor, words", [
    (-0.1, "floor = -0.1: allowed a relative error in [0, 1)"),
    (1.5, "floor = 1.5: allowed"), ("0.005", "floor = '0.005': allowed"),
    (True, "floor = True: allowed")])
def test_a_floor_outside_a_relative_error_is_refused_in_one_line(floor, words):
    name = next(iter(B.READS_FLOOR))
    with pytest.raises(ParameterError, match=re.escape(words)):
        B.validate_bound("step.x.x_max", {"bound": name, "floor": floor, "reason": "r"})
    B.validate_bound("step.x.x_max", {"bound": name, "floor": 0.005, "reason": "r"})


@pytest.mark.parametrize("entry", [{"rel": 0.01, "floor": 0.005, "reason": "r"},
                                   {"bound": "pad-time", "floor": 0.005, "reason": "r"}])
def test_a_floor_no_bound_reads_is_refused(entry):
    """A floor beside a fixed rel, or beside a bound that does not read one, would be
    silently ignored."""
    assert entry.get("bound") in (None, *B.BOUNDS) and "pad-time" not in B.READS_FLOOR
    with pytest.raises(ParameterError, match=r"step\.x\.x_max\.floor: read only with bound"):
        B.validate_bound("step.x.x_max", entry)


def test_a_bound_that_is_not_a_number_is_an_error():
    name = "test-nan"
    B.BOUNDS.pop(name, None)
    B.register(name)(lambda p: B.Bound(math.nan, "?"))
    try:
        with pytest.raises(ValueError, match="rel = nan"):
            B.tree_entry({"bound": name, "reason": "r"}, _pair(1.0, 1.0))
    finally:
        B.BOUNDS.pop(name)


@pytest.mark.parametrize("tree, shown", [("central-leader", True), ("a user's edit", False)])
def test_the_shipped_trees_measurements_are_quoted_on_a_shipped_tree_only(tree, shown):
    """An entry's ``measured`` (the shipped trees' numbers) joins its reason on a shipped
    tree, input for input; on any other tree (here central-leader with one input changed)
    the reason is the physics alone."""
    import dataclasses

    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.compare.tree.ladder import Ladder

    scen = load_scenario("central-leader")
    if not shown:
        scen = dataclasses.replace(scen, t_end=0.05)
    ladder = Ladder(scen, [], {}, {})
    entry = ladder._shown({"rel": 0.01, "reason": "physics", "measured": "0.3 % measured"})
    assert entry["reason"] == ("physics (0.3 % measured)" if shown else "physics")


def test_the_shear_flexibility_is_the_closed_forms():
    """[step.beam_theory]'s delta (compare.runs.bounds.continuum.shear_flexibility) is the shear
    term of the Timoshenko flexibility at a, a / (kappa G A), over the Euler-Bernoulli one
    (1 / K_EB): checked against that closed form on a shipped tree and a low clamp, where the
    shear's share is larger."""
    import dataclasses
    import math

    from treeimpact.analytic.continuum.beam import beam_static_stiffness
    from treeimpact.analytic.model.parameters import DEFAULT_E_OVER_G, DEFAULT_SHEAR_COEFFICIENT
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.compare.runs.bounds.continuum import shear_flexibility

    tree = load_scenario("open-center")
    low = dataclasses.replace(tree, trunk=dataclasses.replace(
        tree.trunk, clamp_height=0.5 * tree.trunk.clamp_height))
    deltas = []
    for scen in (tree, low):
        t = scen.trunk
        assert t.shear_modulus is None and t.shear_coefficient is None  # the defaults
        g, kappa = t.youngs_modulus / DEFAULT_E_OVER_G, DEFAULT_SHEAR_COEFFICIENT
        shear = t.clamp_height / (kappa * g * math.pi * t.diameter ** 2 / 4)
        delta = shear_flexibility(B.Pair(scen, None, "x_max", None, None))
        assert delta == pytest.approx(shear * beam_static_stiffness(t), rel=1e-9)
        deltas.append(delta)
    assert deltas[1] > deltas[0] > 0


def test_the_impulse_ceiling_rests_on_modes_that_give_the_static_flexibility():
    """[step.beam_theory]'s x_max bound sums the clamp's modes, phi_n(a)^2 / omega_n: the
    same modes summed as phi_n(a)^2 / omega_n^2 give the static flexibility at a, which
    beam_static_stiffness solves independently (no modes), on both theories; the shear
    raises the ceiling more than the flexibility (the higher modes shift most) and the
    crown's less."""
    from treeimpact.analytic.continuum.beam import beam_static_stiffness
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.compare.runs.bounds.continuum import impulse_ceiling

    tree = load_scenario("central-leader")
    for theory in ("euler-bernoulli", "timoshenko"):
        flex = impulse_ceiling(tree, 12, theory, "clamp", power=2)
        assert flex == pytest.approx(1 / beam_static_stiffness(tree.trunk, theory), rel=1e-6)
    step = {w: impulse_ceiling(tree, 12, "timoshenko", w) / impulse_ceiling(
        tree, 12, "euler-bernoulli", w) - 1 for w in ("clamp", "crown")}
    delta = beam_static_stiffness(tree.trunk) / beam_static_stiffness(tree.trunk,
                                                                     "timoshenko") - 1
    assert step["clamp"] > delta > step["crown"] > 0
