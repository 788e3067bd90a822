"""Fitting the contact to measured x_max and tau (analytic.paper.contact_fit)."""

import pytest

from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.paper.contact_fit import fit_contact


def test_the_fit_recovers_a_contact_it_generated():
    """Measurements made by the beam itself at a known contact (3 ms, e = 0.3): the fit
    reproduces them (the contact it finds may differ where x_max and tau do not determine
    it uniquely, but the observables must match)."""
    scen = load_scenario("open-center")
    m = simulate_beam(scen, contact_duration=3e-3, restitution=0.3).metrics
    fit = fit_contact(scen, {"x_max": m["x_max"], "t_xmax": m["t_xmax"]}, model="beam")
    # least squares to ftol 1e-8 on relative residuals; t_xmax is refined between samples
    assert fit["rms"] < 2e-3, fit


@pytest.mark.parametrize("measured, field", [({"x_max": -1.0, "t_xmax": 0.01}, "x_max"),
                                             ({"x_max": 0.01}, "t_xmax")])
def test_bad_measurements_are_one_line(measured, field):
    with pytest.raises(ParameterError, match=f"measured.{field}"):
        fit_contact(load_scenario("open-center"), measured)


def test_unknown_model_is_one_line():
    with pytest.raises(ParameterError, match="model"):
        fit_contact(load_scenario("open-center"), {"x_max": 0.01, "t_xmax": 0.015},
                    model="chain")
