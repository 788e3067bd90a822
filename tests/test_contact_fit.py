"""The models held against every measured number (analytic.paper.contact_fit)."""

import math
from dataclasses import replace

import pytest

from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.calibration import with_clamp_mass
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.paper.contact_fit import (
    MODELS,
    TARGETS,
    fit_to_measurements,
    measured_targets,
    read_like_the_paper,
)
from treeimpact.analytic.paper.reproduction import TABLE_1
from treeimpact.analytic.model.options import scenario_as_run


def test_the_fit_recovers_a_contact_it_generated(monkeypatch):
    """Measurements made by the soft model itself at a known contact (3 ms, e = 0.3), read
    as the paper read its trees: the fit explains every one of them (the contact it finds
    may differ where the targets do not fix it, the readings must match), with 6 - 2 = 4
    degrees of freedom left. A coarser global grid than the command's (6 x 4: the test's
    time), and one local fit from its best point, still find the right basin."""
    from treeimpact.analytic.paper import contact_fit

    monkeypatch.setattr(contact_fit, "GRID", {"contact_duration": 6, "restitution": 4})
    monkeypatch.setattr(contact_fit, "STARTS", 1)
    scen = load_scenario("open-center")
    as_run = scenario_as_run(scen, {"contact_duration": 3e-3, "restitution": 0.3})
    measured = read_like_the_paper(simulate_soft(as_run), scen)
    assert all(math.isfinite(v) and v > 0 for v in measured.values()), measured
    fit = fit_to_measurements(scen, measured, model="soft")
    assert fit["dof"] == 4 and set(fit["parameters"]) == {"contact_duration", "restitution"}
    # the readings move in steps of one 0.2 ms sample (T0, tau), so a start on the grid
    # finds the generating contact's readings to within the explained tolerance (5 %)
    assert fit["explains"] == list(TARGETS), fit["targets"]


def test_the_json_names_targets_parameters_bounds_and_dof():
    """The layout of `treeimpact paper --fit-contact --json` (issue 23 item 1), on the
    paper's own model (one free parameter: e)."""
    tree = TABLE_1["central-leader"]
    fit = fit_to_measurements(load_scenario("central-leader"), measured_targets(tree),
                              model="analytic")
    assert fit["dof"] == len(TARGETS) - 1 == 5
    for name, t in fit["targets"].items():
        assert {"measured", "model", "residual", "explained"} <= set(t), name
        assert t["measured"] == measured_targets(tree)[name]
    (e,) = fit["parameters"].values()
    assert {"value", "on_bound"} <= set(e) and 0.01 <= e["value"] <= 0.95


def test_a_parameter_pressed_against_its_range_is_flagged(monkeypatch):
    """Readings of the paper's model at e = 0.3 fitted with e held in [0.01, 0.2]: the fit
    ends on the upper bound and says so; within the range it is not flagged."""
    from treeimpact.analytic.impact.simulate import simulate
    from treeimpact.analytic.paper import contact_fit

    scen = load_scenario("open-center")
    measured = read_like_the_paper(simulate(scenario_as_run(scen, {"restitution": 0.3})), scen)
    free = fit_to_measurements(scen, measured, model="analytic")["parameters"]["restitution"]
    assert not free["on_bound"] and free["value"] == pytest.approx(0.3, abs=0.02)
    monkeypatch.setitem(contact_fit.FREE, "restitution",
                        contact_fit.Free("restitution", 0.01, 0.2))
    (e,) = fit_to_measurements(scen, measured, model="analytic")["parameters"].values()
    assert e["on_bound"] and e["value"] == pytest.approx(0.2), e


def test_the_clamp_mass_moves_on_the_same_measured_tree():
    """with_clamp_mass recalibrates the crown, root spring and damping: M_T, K_T, C_T of
    eqs 7, 8, 10 unchanged to round-off at every clamp mass of the fitted range."""
    scen = load_scenario("open-center")
    ref = reduce_trunk(scen.trunk)
    for m_c in (1.0, 8.0, 16.0):
        t = with_clamp_mass(scen.trunk, m_c, impactor_mass=scen.impactor.mass)
        got = reduce_trunk(t)
        assert t.clamp_mass == m_c
        for field in ("dynamic_mass", "equivalent_stiffness", "equivalent_damping"):
            assert getattr(got, field) == pytest.approx(getattr(ref, field), rel=1e-12)
    assert set(MODELS["beam-clamp"][1]) == {"contact_duration", "restitution", "clamp_mass"}


@pytest.mark.parametrize("field", list(TARGETS))
def test_bad_measurements_are_one_line(field):
    measured = dict(measured_targets(TABLE_1["open-center"]))
    measured[field] = -1.0
    with pytest.raises(ParameterError, match=f"measured.{field}"):
        fit_to_measurements(load_scenario("open-center"), measured)


def test_unknown_model_is_one_line():
    with pytest.raises(ParameterError, match="model"):
        fit_to_measurements(load_scenario("open-center"),
                            measured_targets(TABLE_1["open-center"]), model="chain")


def test_a_billet_scenario_has_no_rebound_angle():
    """The rebound angle needs a pendulum: a run whose impactor has none reads NaN there."""
    from treeimpact.analytic.model.parameters import Billet

    scen = load_scenario("open-center")
    billet = replace(scen, impactor=Billet(mass=132.4, impact_speed=2.2))
    with pytest.raises(AttributeError):
        read_like_the_paper(simulate_soft(billet), billet)


def test_paper_fit_contact_prints_and_writes_every_model_and_target(monkeypatch, capsys):
    """`treeimpact paper --fit-contact` (the paper's own model only, for the test's time):
    the table names every measured number, the dof and what no model explains; the JSON
    carries targets.<name>.{measured, model}, parameters.<name>.{value, on_bound}, dof."""
    import json
    from functools import partial

    from treeimpact.analytic.paper import contact_fit
    from treeimpact.compare.interface.cli import main

    monkeypatch.setattr(contact_fit, "fit_paper_trees",
                        partial(contact_fit.fit_paper_trees, models=("analytic",)))
    assert main(["paper", "--fit-contact"]) == 0
    text = capsys.readouterr().out
    assert "explained by no model" in text and "dof" in text and "theta_b" in text
    assert main(["paper", "--fit-contact", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)["contact_fit"]
    assert set(data) == set(TABLE_1)
    fit = data["open-center"]["fits"]["analytic"]
    assert fit["dof"] == 5 and set(fit["targets"]) == set(TARGETS)
    assert all({"measured", "model"} <= set(t) for t in fit["targets"].values())
    assert {"value", "on_bound"} <= set(fit["parameters"]["restitution"])
