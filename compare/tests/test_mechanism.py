"""The mechanism of the 1-DOF findings: matching the 1-DOF model's impact loss to the
continuum's closes the energy gap (compare.tree.mechanism)."""

import pytest

from treeimpact.analytic.contact.matched_loss import matched_loss_restitution
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.tree.ladder import build_ladder
from treeimpact.compare.tree.mechanism import matched_loss_evidence
from treeimpact.analytic.model.options import scenario_as_run

SCENARIOS = ("open-center", "central-leader", "realistic-crown")


@pytest.mark.parametrize("name", SCENARIOS)
def test_matched_loss_closes_the_energy_gap(name, run_cache):
    """At e = 0.1 the continuum receives 57-213 % more energy than the 1-DOF model; with e*
    such that the 1-DOF impacts lose the continuum's 18-22 J, within 5 % (measured -4.8,
    +3.2, -3.5 %): the loss on the light clamp is the mechanism. x_max keeps a gap of its
    own (+10, +7, -15 %): how the continuum stores the energy."""
    ladder = build_ladder(name, cache=run_cache, engines=())
    ev = matched_loss_evidence(ladder)
    rows = {r["metric"]: r for r in ev["rows"]}
    assert ev["matched_restitution"] > 0.9  # the clamp loses as little as a near-elastic M_T
    assert abs(rows["energy_delivered"]["gap"]) > 0.5
    assert abs(rows["energy_delivered"]["matched_gap"]) < 0.05


def test_matched_restitution_reproduces_the_loss():
    scen = load_scenario("central-leader")
    e = matched_loss_restitution(scen, 20.0)
    got = simulate(scenario_as_run(scen, {"restitution": e}),
                   samples=2).metrics["contact_dissipation"]
    assert got == pytest.approx(20.0, rel=1e-6)  # brentq to 1e-9 in e


@pytest.mark.parametrize("loss", [-1.0, 0.0, 1e4, float("nan")])
def test_a_loss_the_model_cannot_have_is_one_line(loss):
    with pytest.raises(ParameterError, match="contact_loss"):
        matched_loss_restitution(load_scenario("open-center"), loss)
