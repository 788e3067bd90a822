"""The mechanism behind the 1-DOF findings, as evidence: the paper's model with its impact
loss matched to the continuum's (analytic.contact.matched_loss) against the continuum (beam rung).
If the loss is the mechanism, matching it closes the energy gap (docs/whole-event-metrics.md)."""

from __future__ import annotations

import math

from treeimpact.analytic.contact.matched_loss import matched_loss_restitution
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.options import scenario_as_run

from ..runs.rungs import RungKind

#: The quantities compared, with display scale and unit.
MECHANISM_METRICS = (("energy_delivered", 1.0, "J"), ("x_max", 1e3, "mm"),
                     ("crown_peak", 1e3, "mm"))


def matched_loss_evidence(ladder) -> dict | None:
    """{restitution, matched_restitution, rows: [{metric, one_dof, matched, continuum,
    gap, matched_gap}]} for a ladder with a beam rung; ``{"error": ...}`` when the loss cannot
    be matched; None without a beam rung."""
    beam = [r for r in ladder.rungs if r.rung.kind == RungKind.BEAM and r.ok]
    ref = ladder.rungs[0]
    if not beam or not ref.ok:
        return None
    beam = beam[0]
    loss = beam.values.get("contact_dissipation", math.nan)
    try:
        e_star = matched_loss_restitution(ladder.scenario, loss)
    except ParameterError as exc:
        return {"error": str(exc)}
    matched = simulate(scenario_as_run(ladder.scenario, {"restitution": e_star}),
                       samples=2).metrics
    rows = []
    for metric, scale, unit in MECHANISM_METRICS:
        v0, v1, vb = (ref.values.get(metric, math.nan), matched[metric],
                      beam.values.get(metric, math.nan))
        rows.append({"metric": metric, "scale": scale, "unit": unit, "one_dof": v0,
                     "matched": v1, "continuum": vb, "gap": vb / v0 - 1.0,
                     "matched_gap": vb / v1 - 1.0})
    return {"restitution": ladder.scenario.contact.restitution, "matched_restitution": e_star,
            "contact_loss": loss, "one_dof_loss": ref.values.get("contact_dissipation"),
            "rows": rows}
