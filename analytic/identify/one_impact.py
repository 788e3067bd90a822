"""What a record of x alone fixes when the pendulum leaves after one impact: x(t) =
V_1 psi(t; omega_1, zeta), zeta the trunk's damping ratio, V_1 = m (1 + e) u_1 / (M_T + m)
(eqs 21, 54), the same for every (M_T, e) on a curve (the ridge). docs/identification.md,
"What a record fixes"."""

from __future__ import annotations

import math

import numpy as np

from treeimpact.analytic.impact.solver import solve_impacts

from .fit_model import two_body_at
from .fit_parameters import Slot
from .procedure import PendulumTest

#: What a one-impact record leaves undetermined (it fixes omega_1, the trunk's damping ratio,
#: V_1, t0, the offset).
RIDGE = ("M_T", "K_T", "C_T", "restitution", "E")


def one_impact(p, test: PendulumTest, span: float) -> bool:
    """True when the model at p with the pendulum of ``test`` has one impact and no moving
    together within ``span`` s."""
    sol = solve_impacts(two_body_at(p, test), span)
    return len(sol.impacts) == 1 and not sol.together_starts


def on_ridge(p, e: float, test: PendulumTest) -> np.ndarray:
    """The parameters with restitution e and the same omega_1, trunk damping ratio and V_1
    as p (the pendulum's m and u_1 from ``test``): the same record while the pendulum does
    not return (M_T + m = m (1 + e) u_1 / V_1); NaN where that needs M_T <= 0."""
    M, m = math.exp(p[Slot.LN_DYNAMIC_MASS]), test.impactor_mass
    M_e = (M + m) * (1.0 + e) / (1.0 + float(p[Slot.RESTITUTION])) - m
    out = np.array(p, float)
    if not M_e > 0:  # no positive M_T gives that V_1 at this e
        return np.full(out.shape, np.nan)
    out[Slot.LN_DYNAMIC_MASS] = math.log(M_e)
    out[Slot.LN_EQUIVALENT_STIFFNESS] = (p[Slot.LN_EQUIVALENT_STIFFNESS] + math.log(M_e)
                                         - p[Slot.LN_DYNAMIC_MASS])  # omega_1 kept
    out[Slot.RESTITUTION] = e
    return out
