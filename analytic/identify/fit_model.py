"""The model the record fit adjusts: the exact two-body model (eqs 12-35) at a parameter
vector p (:data:`NAMES`), its motion sampled at a record's times."""

from __future__ import annotations

import math

import numpy as np

from treeimpact.analytic.impact.oscillator import Oscillator
from treeimpact.analytic.impact.solver import solve_impacts
from treeimpact.analytic.model.two_body import TwoBodyModel

from .procedure import PendulumTest

#: The parameters p: ln M_T, ln K_T, xi, e, t0 (s), x_offset (m), y_offset (m; the pendulum
#: sensor's, fitted when the record has y), x_drift (m/s) and x_drift2 (m/s^2): the trunk
#: sensor's slow drift, x_offset + x_drift s + x_drift2 s^2 (s = t - t0) added to the
#: motion (each optional: 0 when p is shorter).
NAMES = ("M_T", "K_T", "xi", "e", "t0", "x_offset", "y_offset", "x_drift", "x_drift2")
#: Events one model run may take (impacts, flights, moving together): a tree's record takes
#: tens; a model far from any tree (a 0.01 kg trunk bouncing off the pendulum all record
#: long) is refused (SimulationDiverged) instead of taking seconds.
MAX_EVENTS = 20_000


def two_body_at(p, test: PendulumTest) -> TwoBodyModel:
    """The two-body model (SI) at p: M_T = e^p0, K_T = e^p1, C_T = 2 xi sqrt(K_T M_T)."""
    ln_m, ln_k, xi, e = (float(v) for v in p[:4])
    M, K = math.exp(ln_m), math.exp(ln_k)
    return TwoBodyModel(dynamic_mass=M, damping=2.0 * xi * math.sqrt(K * M), stiffness=K,
                        impactor_mass=test.impactor_mass,
                        impactor_stiffness=test.impactor_stiffness,
                        impact_speed=test.impact_speed, restitution=e)


def drift_at(p, s):
    """The sensor's drift (m) s seconds after the contact: x_drift s + x_drift2 s^2."""
    d1 = float(p[7]) if len(p) > 7 else 0.0
    d2 = float(p[8]) if len(p) > 8 else 0.0
    return (d1 + d2 * s) * s


def model_x(p, test: PendulumTest, t: np.ndarray) -> np.ndarray:
    """x(t) (m) of the exact model with parameters p (:data:`NAMES`)."""
    return model_motion(p, test, t)[0]


def model_motion(p, test: PendulumTest, t: np.ndarray, *, pendulum: bool = False) -> tuple:
    """(x, v) (m, m/s) of the exact model at the sorted times t: :func:`model_x` and the
    trunk's velocity (without the drift's: -dx/dt0 is v and the drift's rate, the fit's
    exact Jacobian column for t0); with ``pendulum`` also the pendulum's (y, v_y) in the
    same frame (y = x at contact, y = 0 at the first one): before it, the free swing at u_1
    (eq 13) run back from the contact."""
    t0 = float(p[4])
    s = t - t0
    x, v = float(p[5]) + drift_at(p, s), np.zeros(t.shape)
    first = int(np.searchsorted(t, t0, side="right"))  # the first sample after the contact
    sol = None
    if first < t.size:
        t_rel = t[first:] - t0
        sol = solve_impacts(two_body_at(p, test), float(t_rel[-1]), max_events=MAX_EVENTS)
        rows = sol.sorted_state(np.minimum(t_rel, sol.t_end), pendulum=pendulum)
        x[first:] += rows[0]
        v[first:] = rows[1]
    if not pendulum:
        return x, v
    y, vy = np.full(t.shape, float(p[6])), np.empty(t.shape)
    swing = Oscillator.from_mck(test.impactor_mass, 0.0, test.impactor_stiffness)
    dy, vy[:first] = swing.advance(t[:first] - t0, 0.0, test.impact_speed, np)
    y[:first] += dy
    if sol is not None:
        y[first:] += rows[2]
        vy[first:] = rows[3]
    return x, v, y, vy
