"""A tree's scenario from measured M_T, K_T, b: the reduction inverted (analytic.model.calibration),
the scenario file written (analytic.model.scenario_toml) and `treeimpact scenario`."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.calibration import (
    MeasuredTree,
    calibrate_trunk,
    damping_rate_from_regression,
    stiffness_from_regression,
)
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.scenario import load_scenario, scenario_from_dict, shipped_scenarios
from treeimpact.analytic.model.scenario_toml import scenario_toml
from treeimpact.analytic.paper.reproduction import TABLE_1
from treeimpact.compare.interface.cli import main


@pytest.mark.parametrize("name", ["open-center", "central-leader"])
def test_shipped_trees_are_the_calibration_of_table_1(name):
    """The shipped files' calibrated values (written to 9 digits by hand) come back from
    Table 1's M_T, K_T and the regression's b = -a2/a1."""
    shipped = load_scenario(name)
    tab = TABLE_1[name]
    measured = MeasuredTree(tab.dynamic_mass, tab.equivalent_stiffness,
                            damping_rate_from_regression(tab.a1, tab.a2))
    trunk = calibrate_trunk(shipped.trunk, measured, impactor_mass=shipped.impactor.mass)
    for field in ("crown_mass", "damping", "base_stiffness"):
        # the files hold 9 significant digits
        assert getattr(trunk, field) == pytest.approx(getattr(shipped.trunk, field), rel=1e-8)


def test_calibrated_trunk_reduces_to_the_measured_properties():
    chosen = load_scenario("central-leader").trunk
    measured = MeasuredTree(dynamic_mass=150.0, equivalent_stiffness=9e5, damping_rate=25.0)
    trunk = calibrate_trunk(chosen, measured, impactor_mass=100.0)
    sdof = reduce_trunk(trunk)  # the forward reduction, eqs 7, 8, 10
    assert sdof.dynamic_mass == pytest.approx(150.0, rel=1e-12)
    assert sdof.equivalent_stiffness == pytest.approx(9e5, rel=1e-12)
    assert sdof.equivalent_damping == pytest.approx(2 * 25.0 * (150.0 + 100.0), rel=1e-12)  # eq 34


def test_stiffness_at_the_rigid_clamp_needs_no_root_spring():
    chosen = load_scenario("central-leader").trunk
    rigid = 3 * chosen.bending_stiffness / chosen.clamp_height ** 3  # eq 8
    trunk = calibrate_trunk(chosen, MeasuredTree(110.0, rigid, 30.0), impactor_mass=132.4)
    assert math.isinf(trunk.base_stiffness)


def test_impossible_measurements_are_one_line_errors_naming_the_quantity():
    chosen = load_scenario("central-leader").trunk
    with pytest.raises(ParameterError, match=r"^equivalent_stiffness = .* above the rigid-clamp"):
        calibrate_trunk(chosen, MeasuredTree(110.0, 1e9, 30.0), impactor_mass=132.4)
    with pytest.raises(ParameterError, match=r"^dynamic_mass = 1 kg: below the bare trunk"):
        calibrate_trunk(chosen, MeasuredTree(1.0, 1e6, 30.0), impactor_mass=132.4)
    for bad in (dict(dynamic_mass=-1.0), dict(equivalent_stiffness=math.nan),
                dict(damping_rate=-2.0)):
        with pytest.raises(ParameterError, match=f"^{next(iter(bad))} = "):
            MeasuredTree(**{**dict(dynamic_mass=1.0, equivalent_stiffness=1.0,
                                   damping_rate=1.0), **bad})


@pytest.mark.parametrize("name", ["open-center", "central-leader"])
def test_regression_gives_the_printed_natural_frequency(name):
    """omega_n of eq 43 from Table 1's regression matches the printed 79.2 / 84.4 rad/s (to
    its rounding); K_T of eq 46 then follows from it and M_T."""
    tab = TABLE_1[name]
    m, k = 132.4, 132.4 * 9.81 / 1.51
    k_t = stiffness_from_regression(a1=tab.a1, a2=tab.a2, x_max=tab.x_max, tau=tab.tau,
                                    dynamic_mass=tab.dynamic_mass, impactor_mass=m,
                                    impactor_stiffness=k)
    omega_n = math.sqrt((k_t + k) / (tab.dynamic_mass + m))
    assert omega_n == pytest.approx(tab.omega_n, abs=0.06)  # printed to 0.1 rad/s
    with pytest.raises(ParameterError, match=r"^x_max = .* overdamped"):
        stiffness_from_regression(a1=tab.a1, a2=tab.a2, x_max=1.0, tau=tab.tau,
                                  dynamic_mass=tab.dynamic_mass, impactor_mass=m,
                                  impactor_stiffness=k)


@pytest.mark.parametrize("name", shipped_scenarios())
def test_scenario_file_round_trips(name):
    s = load_scenario(name)
    again = scenario_from_dict(tomllib.loads(scenario_toml(s)), "other")
    assert again == s and again.notes == s.notes
    rigid = dataclasses.replace(s, trunk=dataclasses.replace(s.trunk, base_stiffness=math.inf))
    assert scenario_from_dict(tomllib.loads(scenario_toml(rigid))) == rigid


TEST = ["--clamp-height", "0.315", "--diameter", "0.126", "--impactor-mass", "132.4",
        "--equivalent-length", "1.51", "--release-angle-deg", "36.39", "--youngs-modulus", "12.6e9",
        "--dynamic-mass", "110"]


def test_scenario_command_writes_a_file_that_simulates_like_the_shipped_tree(tmp_path, capsys):
    code = main(["scenario", "my-tree", *TEST, "--equivalent-stiffness", "1.5e6", "--a1", "1.167",
                 "--a2", "-34.817", "--out", str(tmp_path)])
    assert code == 0
    written = load_scenario(tmp_path / "my-tree.toml")
    shipped = load_scenario("central-leader")
    assert written.notes["calibrated"].startswith("m_f from M_T = 110 kg")
    sdof, ref = reduce_trunk(written.trunk), reduce_trunk(shipped.trunk)
    assert sdof.dynamic_mass == pytest.approx(ref.dynamic_mass, rel=1e-8)
    assert sdof.equivalent_stiffness == pytest.approx(ref.equivalent_stiffness, rel=1e-8)
    assert sdof.equivalent_damping == pytest.approx(ref.equivalent_damping, rel=1e-8)


@pytest.mark.parametrize("extra, words", [
    ([], "--damping-rate: missing"),
    (["--damping-rate", "30"], "--equivalent-stiffness: missing"),
    (["--damping-rate", "30", "--a1", "1.2", "--equivalent-stiffness", "1e6"], "not both"),
    (["--damping-rate", "30", "--equivalent-stiffness", "1e9"], "above the rigid-clamp"),
    (["--damping-rate", "x", "--equivalent-stiffness", "1e6"], "--damping-rate: expected a number"),
])
def test_scenario_command_bad_input_is_one_line_and_exit_2(extra, words, capsys):
    assert main(["scenario", "t", *TEST, *extra]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
