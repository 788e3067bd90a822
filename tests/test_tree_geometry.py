"""A tree from its geometry (issue 50 item 6): ``treeimpact scenario --crown-mass`` and
``ti.tree_scenario(crown_mass=...)`` build a scenario from what an orchard gives, without a
pendulum test; what it assumes (the root spring, the damping, E and rho when not given)
comes from the registry with its value, range and reason, and enters the sensitivity study
as unmeasured inputs (compare.studies.study_inputs.vary)."""

from __future__ import annotations

import dataclasses
import math
import re
import tomllib

import pytest

import treeimpact as ti
from treeimpact.analytic.model.assumed import ASSUMABLE
from treeimpact.analytic.model.reduction import (
    mass_parts,
    printed_damping,
    printed_dynamic_mass,
    printed_stiffness,
    reduce_trunk,
)
from treeimpact.analytic.model.registry import ASSUMED, BY_NAME
from treeimpact.analytic.model.scenario import load_scenario, scenario_from_dict
from treeimpact.analytic.model.scenario_toml import scenario_toml
from treeimpact.analytic.paper.reproduction import PENDULUM_MASS, TABLE_1
from treeimpact.compare.interface.cli import main
from treeimpact.compare.report import mass_origin
from treeimpact.compare.studies.sensitivity import design
from treeimpact.compare.studies.study_inputs import free_inputs, inputs_of, vary

#: The issue's young plum: what an orchard gives (SI), no pendulum test.
PLUM = {"clamp_height": 0.35, "diameter": 0.12, "impactor_mass": 20.0,
        "equivalent_length": 1.5, "release_angle_deg": 30.0, "length": 1.1,
        "crown_mass": 25.0}


def _argv(name="plum", **inputs):
    return ["scenario", name, *[a for k, v in inputs.items()
                                for a in (f"--{k.replace('_', '-')}", repr(v))]]


def test_the_command_and_the_api_build_the_same_scenario(capsys):
    assert main(_argv(**PLUM)) == 0
    assert capsys.readouterr().out == scenario_toml(ti.tree_scenario("plum", **PLUM))


def test_m_t_k_t_c_t_are_eqs_7_8_10_by_the_printed_closed_forms():
    """The assumed root is the paper's rigid clamp, so the paper's printed closed forms
    after eqs 7, 8 and 10 (an evaluation independent of the reduction's polynomial
    integrals) give M_T, K_T and C_T (the printed C_T's factor 1/2 undone, DISCREPANCIES);
    the damping ratio (eq 14) is the registry's assumed one. 1e-12: round-off of sums of a
    few terms."""
    trunk = ti.tree_scenario("plum", **PLUM).trunk
    tree = reduce_trunk(trunk)
    assert math.isinf(trunk.base_stiffness) and trunk.crown_mass == PLUM["crown_mass"]
    assert tree.dynamic_mass == pytest.approx(printed_dynamic_mass(trunk), rel=1e-12)
    assert tree.equivalent_stiffness == pytest.approx(printed_stiffness(trunk), rel=1e-12)
    assert tree.equivalent_damping == pytest.approx(2.0 * printed_damping(trunk), rel=1e-12)
    assert tree.damping_ratio == pytest.approx(ASSUMED["damping"].value, rel=1e-12)
    assert trunk.youngs_modulus == ASSUMED["youngs_modulus"].value
    assert trunk.density == ASSUMED["density"].value


def test_the_first_screen_line_says_where_the_geometry_tree_s_m_t_comes_from():
    """mass_origin of the geometry tree: its parts (eq 7) add up to the printed M_T and the
    crown counts ((3 l - a) / (2 a))^2 times (the rigid clamp's static shape)."""
    trunk = ti.tree_scenario("plum", **PLUM).trunk
    parts = mass_parts(trunk)
    a, l = trunk.clamp_height, trunk.length
    assert parts.crown_weight == pytest.approx(((3 * l - a) / (2 * a)) ** 2, rel=1e-12)
    text = mass_origin(trunk)
    shown = float(re.match(r"M_T = ([\d.]+) kg", text).group(1))
    assert shown == pytest.approx(printed_dynamic_mass(trunk), rel=5e-3), text  # 3 digits
    assert "25 kg counted" in text and "assumed" not in text  # no fields named: none
    scen = ti.tree_scenario("plum", **PLUM)
    text = mass_origin(trunk, scen.notes["assumed"])
    for f in scen.notes["assumed"]:
        assert BY_NAME[f.split(".")[1]].label in text, f
    assert text.count("\n") == 0 and "no pendulum test" in text


def test_given_e_and_density_are_kept_and_not_assumed():
    scen = ti.tree_scenario("plum", **PLUM, youngs_modulus=8e9, density=700.0)
    assert (scen.trunk.youngs_modulus, scen.trunk.density) == (8e9, 700.0)
    assert scen.notes["assumed"] == ["trunk.base_stiffness", "trunk.damping"]
    assert scen.notes["measured"] == ["trunk.density"]
    assert "E = 8e+09 Pa" in scen.notes["given"] and "rho = 700 kg/m^3" in scen.notes["given"]


def test_the_notes_name_every_assumption_with_its_value_range_and_reason():
    notes = ti.tree_scenario("plum", **PLUM).notes
    assert notes["assumed"] == list(ASSUMABLE)
    assert not set(notes["assumed"]) & set(notes.get("measured", ()))
    assert not set(notes.get("measured", ())) & set(ASSUMABLE)
    for field in ASSUMABLE:
        key = field.split(".")[1]
        a, text = ASSUMED[key], notes[f"assumed_{key}"]
        assert a.why in text, key
        assert f"range {a.low:g}-{a.high:g}" in text, key
        assert f"{BY_NAME[a.via].symbol} = {a.value:g}" in text, key
    for key in ("given", "chosen", "derived"):
        assert notes[key], key
    assert "no pendulum test" in notes["derived"]


def test_the_written_file_loads_back_and_runs_on_two_rungs(tmp_path, capsys):
    """The file written loads back equal (notes included) and runs: the analytic model and
    the continuum (short t_end); the beam's static stiffness at the clamp is 3 E I / a^3,
    eq 8 with the rigid clamp (1e-9: the cubic elements are exact for a point load at a
    node; the rest is the FE solve's round-off)."""
    assert main([*_argv(**PLUM), "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    path = tmp_path / "plum.toml"
    written = load_scenario(path)
    assert written == ti.tree_scenario("plum", **PLUM)
    analytic = ti.simulate(str(path))
    assert analytic.model.M_T == pytest.approx(reduce_trunk(written.trunk).dynamic_mass,
                                               rel=1e-12)  # the same eq 7, one sum
    beam = ti.simulate(str(path), backend="beam", t_end=0.02)  # short: past the separation
    for m in (analytic.metrics, beam.metrics):
        assert math.isfinite(m.x_max) and m.x_max > 0
    modes = ti.modes(str(path), backend="beam")
    assert modes.beam.static_stiffness == pytest.approx(printed_stiffness(written.trunk),
                                                        rel=1e-9)


def test_a_file_cannot_list_a_field_both_measured_and_assumed():
    data = tomllib.loads(scenario_toml(ti.tree_scenario("plum", **PLUM)))
    data["calibration"]["measured"] = ["trunk.density"]
    with pytest.raises(ti.ParameterError, match="also listed measured"):
        scenario_from_dict(data)
    data["calibration"]["measured"] = []
    data["calibration"]["assumed"] = ["trunk.crown_mass"]
    with pytest.raises(ti.ParameterError, match="calibration.assumed: 'trunk.crown_mass'"):
        scenario_from_dict(data)


@pytest.mark.parametrize("extra, words", [
    (["--dynamic-mass", "300"], "--crown-mass: a tree from its geometry (--crown-mass) or a "
     "measured tree (--dynamic-mass, ...), not both; given --crown-mass, --dynamic-mass"),
    (["--damping-rate", "30"], "given --crown-mass, --damping-rate"),
    (["--a1", "1.2", "--a2", "-30"], "given --crown-mass, --a1, --a2"),
    (["--x-max", "0.01"], "given --crown-mass, --x-max"),
    (["--crown-mass", "-1"], "--crown-mass = -1.0 kg is out of range: allowed [0, 10000] kg"),
    (["--crown-mass", "2e4"], "--crown-mass = 20000.0 kg is out of range"),
    (["--youngs-modulus", "5"], "--youngs-modulus = 5.0 Pa is out of range"),
    (["--crown-mass", "9000", "--diameter", "2.5"], "--crown-mass = 9000 kg: the assumed "
     "damping ratio 0.582 (eq 14) needs a trunk damping"),
])
def test_refusals_are_one_line_exit_2_naming_the_flag(extra, words, capsys):
    assert main([*_argv(**PLUM), *extra]) == 2  # a flag typed twice: argparse's last
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1, err


def test_neither_way_is_refused_naming_both(capsys):
    argv = _argv(**{k: v for k, v in PLUM.items() if k != "crown_mass"})
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--dynamic-mass: missing" in err and "--crown-mass" in err and err.count("\n") == 1


def test_the_api_names_keywords_when_the_ways_are_mixed():
    with pytest.raises(ti.ParameterError) as info:
        ti.tree_scenario("plum", **PLUM, dynamic_mass=300.0)
    text = str(info.value)
    assert "--" not in text and text.startswith("crown_mass: a tree from its geometry")


def test_the_assumed_ranges_are_the_paper_s_two_trees():
    """The damping ratio C_T / (2 sqrt(K_T M_T)) (eq 14) with C_T = 2 b (M_T + m) (eq 34)
    and b = -a2/a1 (eq 42), and E = K_T a^3 / (3 I) (eq 47), recomputed from Table 1: the
    registry's declared range ends are theirs and its values their mean (5e-4: the three
    digits the registry declares them to)."""
    xi, e_mod = [], []
    for t in TABLE_1.values():
        c_t = 2.0 * (-t.a2 / t.a1) * (t.dynamic_mass + PENDULUM_MASS)
        xi.append(c_t / (2.0 * math.sqrt(t.equivalent_stiffness * t.dynamic_mass)))
        e_mod.append(t.equivalent_stiffness * t.clamp_height ** 3
                     / (3.0 * math.pi * t.diameter ** 4 / 64))
    damping, young = ASSUMED["damping"], ASSUMED["youngs_modulus"]
    assert (damping.low, damping.high) == pytest.approx((min(xi), max(xi)), abs=5e-4)
    assert damping.value == pytest.approx(sum(xi) / 2, abs=5e-4)
    assert (young.low, young.high) == pytest.approx((min(e_mod), max(e_mod)), rel=5e-4)
    assert young.value == pytest.approx(sum(e_mod) / 2, rel=5e-4)
    assert ASSUMED["base_stiffness"].value == 0.0  # the paper's rigid clamp: no root share
    for name, a in ASSUMED.items():
        via = BY_NAME[a.via]
        assert via.low <= a.low <= a.value <= a.high <= via.high, name
        if via.unmeasured is not None:  # the study varies it over the range stated here
            assert (via.unmeasured.low, via.unmeasured.high) == (a.low, a.high), name


def test_the_study_varies_a_geometry_tree_s_assumptions_and_keeps_its_geometry():
    """A tree from its geometry: the study's inputs add its damping ratio and its assumed E;
    at its own inputs vary() gives the tree back (1e-12); at every design point l, a, d and
    the crown are kept; the assumed E is eq 47's rigid-clamp modulus (wood and root
    together), so the point's E sets K_T = 3 E I / a^3 and the root share only splits that
    flexibility (the wood's E = E / (1 - share), eq 8 with the root spring); the damping
    ratio is the point's (eq 14), so K_T and C_T move. 1e-9: round-off of the reduction's
    sums."""
    scen = ti.tree_scenario("plum", **PLUM)
    names = free_inputs(scen)
    assert names[-2:] == ("damping_ratio", "youngs_modulus") and "root_share" in names
    own = inputs_of(scen)
    back, _ = vary(scen, own)
    for f in dataclasses.fields(scen.trunk):
        a, b = getattr(back.trunk, f.name), getattr(scen.trunk, f.name)
        assert a == b or a == pytest.approx(b, rel=1e-12), f.name
    stiffness, damping = set(), set()
    for row in design(2, names=names):
        p = own | dict(zip(names, row))
        varied, _ = vary(scen, p)
        t = varied.trunk
        for f in ("length", "clamp_height", "diameter", "crown_mass"):
            assert getattr(t, f) == getattr(scen.trunk, f), f
        share = p["root_share"]
        assert t.youngs_modulus == pytest.approx(p["youngs_modulus"] / (1 - share), rel=1e-15)
        tree = reduce_trunk(t)
        both = 3.0 * p["youngs_modulus"] * t.second_moment / t.clamp_height ** 3
        assert tree.equivalent_stiffness == pytest.approx(both, rel=1e-9)
        assert tree.damping_ratio == pytest.approx(p["damping_ratio"], rel=1e-9)
        stiffness.add(round(tree.equivalent_stiffness))
        damping.add(round(tree.equivalent_damping, 3))
    assert len(stiffness) > 1 and len(damping) > 1


def test_a_given_e_is_held_by_the_study():
    """E given: the study does not vary it (only the assumptions enter as unmeasured
    inputs), and a given density is held too (listed measured)."""
    scen = ti.tree_scenario("plum", **PLUM, youngs_modulus=8e9, density=700.0)
    names = free_inputs(scen)
    assert "youngs_modulus" not in names and "density" not in names
    assert names[-1] == "damping_ratio"
    for row in design(1, names=names):
        p = inputs_of(scen) | dict(zip(names, row))
        varied, _ = vary(scen, p)
        t = varied.trunk
        assert (t.youngs_modulus, t.density) == (8e9, 700.0)
        # the wood's own E: the root spring adds its share (eq 8); 1e-9: the sums' round-off
        rigid = 3.0 * t.bending_stiffness / t.clamp_height ** 3
        assert reduce_trunk(t).equivalent_stiffness == pytest.approx(
            (1 - p["root_share"]) * rigid, rel=1e-9)


def test_a_measured_tree_s_study_is_unchanged():
    """A shipped (measured) tree varies the six inputs it did, not the damping ratio."""
    scen = load_scenario("central-leader")
    assert "damping_ratio" not in free_inputs(scen)
    assert "damping_ratio" not in inputs_of(scen)
    assert "assumed" not in scen.notes
