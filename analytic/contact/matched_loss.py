"""The matched-loss 1-DOF model: the paper's model with e chosen so that its impacts lose
what a flexible trunk's contact loses over the whole event (the mechanism test of
docs/whole-event-metrics.md). SI units."""

from __future__ import annotations

import math

from scipy.optimize import brentq

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.parameters import Scenario, check_range
from treeimpact.analytic.model.options import scenario_as_run

#: Newton's contact loss is continuous and decreasing in e on [0, 1); e = 1 loses nothing.
_E_LOW, _E_HIGH = 0.0, 1.0 - 1e-6


def matched_loss_restitution(scenario: Scenario, contact_loss: float, *,
                             xtol: float = 1e-9) -> float:
    """e in [0, 1) for which the exact 1-DOF model of ``scenario`` loses ``contact_loss``
    (J) in its whole-event contact dissipation (eq 56 summed over every impact), to
    ``xtol`` in e (Brent's method). One-line error when the loss is outside what e in
    [0, 1) can give: (0, the plastic loss 1/2 mu u1^2]."""
    check_range("contact_loss", contact_loss, low=0, low_open=True, unit="J")

    def excess(e):
        return simulate(scenario_as_run(scenario, {"restitution": e}),
                        samples=2).metrics["contact_dissipation"] \
            - contact_loss

    hi, lo = excess(_E_LOW), excess(_E_HIGH)
    if not (math.isfinite(hi) and math.isfinite(lo)):
        raise ParameterError("contact_loss: the 1-DOF model's bodies do not part within t_end")
    if not lo <= 0.0 <= hi:
        raise ParameterError(f"contact_loss: {contact_loss:.6g} J outside what the 1-DOF "
                             f"model can lose, [{lo + contact_loss:.6g}, "
                             f"{hi + contact_loss:.6g}] J for e in [0, 1)")
    return float(brentq(excess, _E_LOW, _E_HIGH, xtol=xtol))
