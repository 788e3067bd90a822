"""The record fit's reported quantities with 95 % intervals: from the Jacobian at the optimum
(the delta method in a variable spanning the physical range), widened over the restitutions
the record cannot rule out (e's profile), and the ranges of a one-impact record's ridge.
docs/identification.md, "Intervals" and "What a record fixes"."""

from __future__ import annotations

import math

import numpy as np

from treeimpact.analytic.model.registry import units_of

from .fit_parameters import E_MAX, FitVariables, Slot
from .fitter import Fit, Fitter, Problem
from .one_impact import RIDGE, on_ridge
from .procedure import PendulumTest, youngs_modulus
from .profile import Z95, Ridge, RestitutionProfile

#: The two damping ratios a fit reports, by name: the trunk's own (the fit's parameter) and
#: the moving-together pair's, the paper's xi = b / omega_n (eqs 42-43), which the paper's
#: procedure and the report's truth give (docs/glossary.md).
DAMPING_RATIOS = ("trunk_damping_ratio", "pair_damping_ratio")
DAMPING_RATIO_FORMULAS = {
    "trunk_damping_ratio": "C_T / (2 sqrt(K_T M_T)): the trunk alone",
    "pair_damping_ratio": "b / omega_n = C_T / (2 sqrt((K_T + k)(M_T + m))): the trunk and "
                          "pendulum moving together, the paper's xi (eqs 42-43)"}
#: Every quantity a fit reports (SI; y_offset only with a pendulum record), and their units.
QUANTITIES = ("M_T", "K_T", "C_T", *DAMPING_RATIOS, "restitution", "E", "omega_1", "V_1",
              "t0", "x_offset", "x_drift", "x_drift2")
UNITS = {**units_of("M_T", "K_T", "C_T"), "trunk_damping_ratio": "1",
         "pair_damping_ratio": "1", **units_of("restitution", "E"), "omega_1": "rad/s",
         "V_1": "m/s", "t0": "s", "x_offset": "m", "x_drift": "m/s", "x_drift2": "m/s^2",
         "y_offset": "m"}
#: The quantities that are positive by nature (intervals in their logarithm).
POSITIVE = ("M_T", "K_T", "C_T", *DAMPING_RATIOS, "E", "omega_1", "V_1")
#: What the tree's response fixes (not a record without an impact): all but the sensor's.
TREE = (*POSITIVE, "restitution", "t0")
#: A quantity is determined by a record when its 95 % interval is bounded and, for the
#: positive ones and e, its high end at most this factor of its low end (M_T in 50-100 kg
#: is determined, in 50-101 kg or 0-10 kg not): else "not fixed", its range the answer.
DETERMINED_FACTOR = 2.0
#: The nuisance quantities, each a parameter of the fit reported as fitted.
NUISANCE = {"t0": Slot.T0, "x_offset": Slot.X_OFFSET, "x_drift": Slot.X_DRIFT,
            "x_drift2": Slot.X_DRIFT2, "y_offset": Slot.Y_OFFSET}


def estimates(p, cov, test: PendulumTest, *, pendulum: bool = False) -> tuple[dict, dict]:
    """Values (SI) and 95 % intervals of every reported quantity at p with covariance cov
    (slot order) for the pendulum of ``test``, by the delta method in a variable spanning
    the physical range: logarithms for the
    positive ones (M_T, K_T, C_T, the damping ratios, E, omega_1, V_1), asin(sqrt(e)) in
    [0, pi/2] for e; the pendulum sensor's offset too if ``pendulum``. The two damping ratios
    are :data:`DAMPING_RATIOS`."""
    M, K = math.exp(p[Slot.LN_DYNAMIC_MASS]), math.exp(p[Slot.LN_EQUIVALENT_STIFFNESS])
    zeta, e = float(p[Slot.TRUNK_DAMPING_RATIO]), float(p[Slot.RESTITUTION])  # trunk's
    m, u1, k = test.impactor_mass, test.impact_speed, test.impactor_stiffness
    C = 2.0 * zeta * math.sqrt(K * M)
    pair = C / (2.0 * math.sqrt((K + k) * (M + m)))  # b / omega_n, eqs 42-43
    e_mod = youngs_modulus(K, test.clamp_height, test.diameter)  # eq 47
    omega = math.sqrt(K / M)  # eq 14: omega_1^2 = K_T / M_T
    v1 = m * (1.0 + e) * u1 / (M + m)  # eq 21 at the first impact, trunk at rest

    def sd(**gradient):  # standard deviation of gradient . p, by slot
        g = np.zeros(cov.shape[0])
        for name, value in gradient.items():
            g[Slot[name]] = value
        return math.sqrt(max(float(g @ cov @ g), 0.0))

    z = Z95
    values = {"M_T": M, "K_T": K, "C_T": C, "trunk_damping_ratio": zeta,
              "pair_damping_ratio": pair, "restitution": e, "E": e_mod, "omega_1": omega,
              "V_1": v1}
    intervals = {
        "M_T": log_interval(M, z * sd(LN_DYNAMIC_MASS=1)),
        "K_T": log_interval(K, z * sd(LN_EQUIVALENT_STIFFNESS=1)),
        "C_T": log_interval(C, z * sd(LN_DYNAMIC_MASS=0.5, LN_EQUIVALENT_STIFFNESS=0.5,
                                      TRUNK_DAMPING_RATIO=1.0 / zeta)),
        "trunk_damping_ratio": log_interval(zeta, z * sd(TRUNK_DAMPING_RATIO=1.0 / zeta)),
        "pair_damping_ratio": log_interval(pair, z * sd(
            LN_DYNAMIC_MASS=0.5 * m / (M + m), LN_EQUIVALENT_STIFFNESS=0.5 * k / (K + k),
            TRUNK_DAMPING_RATIO=1.0 / zeta)),
        "restitution": restitution_interval(e, z * sd(RESTITUTION=1)),
        "E": log_interval(e_mod, z * sd(LN_EQUIVALENT_STIFFNESS=1)),
        "omega_1": log_interval(omega, z * sd(LN_DYNAMIC_MASS=-0.5, LN_EQUIVALENT_STIFFNESS=0.5)),
        "V_1": log_interval(v1, z * sd(LN_DYNAMIC_MASS=-M / (M + m),
                                       RESTITUTION=1.0 / (1.0 + e))),
    }
    for name, slot in NUISANCE.items():
        if slot == Slot.Y_OFFSET and not pendulum:
            continue
        w = z * sd(**{slot.name: 1})
        values[name] = float(p[slot])
        intervals[name] = (p[slot] - w, p[slot] + w)
    return values, {k: (float(lo), float(hi)) for k, (lo, hi) in intervals.items()}


def log_interval(value: float, half_width: float) -> tuple[float, float]:
    """(value e^-w, value e^w) for a parameter fitted in logarithm with ``half_width`` w: a w
    beyond float range (a direction the record does not determine) gives (0, inf) as
    such, not an overflow; NaN stays NaN."""
    w = float(half_width)
    if not w < 700.0:  # e^700 ~ 1e304; NaN fails the test too and stays NaN below
        return (0.0, math.inf) if w == w else (math.nan, math.nan)
    return value * math.exp(-w), value * math.exp(w)


def restitution_interval(e: float, half_width: float) -> tuple[float, float]:
    """The interval of e with ``half_width`` w (in e) mapped through phi = asin(sqrt(e)), whose
    range [0, pi/2] is e's [0, 1]: phi +- w dphi/de, clipped to that range, mapped back. At
    e = 0 or 1 (dphi/de infinite) it reaches the far end of the range; NaN stays NaN."""
    w = float(half_width)
    if w != w:
        return math.nan, math.nan
    if w == 0.0:  # e held (given): its interval is its value, exactly
        return e, e
    phi = math.asin(math.sqrt(min(max(e, 0.0), 1.0)))
    slope = 0.5 / math.sqrt(e * (1.0 - e)) if 0.0 < e < 1.0 else math.inf
    half = w * slope if w > 0 else 0.0
    lo, hi = max(0.0, phi - half), min(0.5 * math.pi, phi + half)
    return math.sin(lo) ** 2, math.sin(hi) ** 2


def determined(name: str, interval) -> bool:
    """Whether a record determines the quantity ``name`` with this 95 % interval: bounded
    and, for a positive quantity or e, narrower than DETERMINED_FACTOR (high / low)."""
    lo, hi = interval
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return False
    if name in POSITIVE or name == "restitution":
        return lo > 0.0 and hi <= DETERMINED_FACTOR * lo
    return True


def widened_over_profile(best: Fit, profile: RestitutionProfile, intervals: dict,
                         test: PendulumTest, floor: float, threshold: float, *,
                         pendulum: bool, basin_threshold: float | None = None) -> dict:
    """``intervals`` widened over the restitutions the record cannot rule out: each point of
    e's ``profile`` within ``threshold`` of the ``best`` fit, with the others' uncertainty at
    that e (the covariance given e, residual variance at least ``floor`` m squared, of the
    pendulum ``test``; its sensor offset too if ``pendulum``); e's own from the Jacobian
    where the cost is quadratic in it (e off its bounds, its interval under 0.2 wide),
    hulled with the profile's range, else the profile's range alone. Another valley of the
    profile within ``basin_threshold`` (the joint 95 % threshold of every fitted parameter:
    choosing a basin chooses them all) widens them too, with its own covariance given e
    (the Jacobian at its point), e's range included."""
    p, out = best.p, dict(intervals)
    given = best.problem.covariance(p, floor, given_e=True)
    e_lo, e_hi = out["restitution"]
    local = 0.02 < p[Slot.RESTITUTION] < E_MAX - 0.02 and e_hi - e_lo < 0.2
    if not local:  # e at a bound or the cost not quadratic in it: the profile alone
        _, out = estimates(p, given, test, pendulum=pendulum)
    basins = profile.basins(best, basin_threshold) if basin_threshold is not None else []
    own = [best.problem.covariance(q, floor, given_e=True) for q in basins]  # its own
    for q, cov in [*((q, given) for q in profile.inside(best, threshold)), *zip(basins, own)]:
        _, iv = estimates(q, cov, test, pendulum=pendulum)
        for k in RIDGE + DAMPING_RATIOS + ("omega_1", "V_1"):
            out[k] = (min(out[k][0], iv[k][0]), max(out[k][1], iv[k][1]))
    lo, hi = profile.e_range(best, threshold)
    for q in basins:
        lo, hi = min(lo, q[Slot.RESTITUTION]), max(hi, q[Slot.RESTITUTION])
    e = p[Slot.RESTITUTION]
    out["restitution"] = ((min(out["restitution"][0], lo), max(out["restitution"][1], hi))
                          if local else (min(lo, e), max(hi, e)))
    return out


def ridge_estimates(ridge: Ridge, fitter: Fitter, keep, test: PendulumTest, floor: float,
                    values: dict, intervals: dict) -> tuple[dict, dict, dict, str]:
    """Values and ranges of a one-impact record: the fixed quantities as fitted, M_T, K_T,
    C_T, E and e not fixed: ranges from the 95 % low at the profile's lowest acceptable e
    to the 95 % high at e = 1 on the ``ridge`` (the Jacobian in the other parameters at both
    ends, on the samples ``keep`` selects of ``fitter``'s record, residual variance at least
    ``floor`` m squared, of the pendulum ``test``), and over the profile's points between.
    ``values`` and ``intervals``: the fit's. Returns (values, intervals, determined,
    note)."""
    at_e: FitVariables = fitter.params.freeze(Slot.RESTITUTION)
    tk, xk = fitter.t[keep], fitter.x[keep]
    intervals = dict(intervals)
    determined = {k: k not in RIDGE for k in values}
    for pe in (ridge.low, on_ridge(ridge.one, 1.0, test)):
        prob = Problem(tk, xk, None, test, fitter.scale, at_e, pe)
        _, iv = estimates(pe, prob.covariance(pe, floor), test)
        for k in RIDGE:
            intervals[k] = (min(intervals[k][0], iv[k][0]), max(intervals[k][1], iv[k][1]))
    values = {k: (math.nan if k in RIDGE else v) for k, v in values.items()}
    intervals["restitution"] = (min(ridge.e_low, intervals["restitution"][0]), 1.0)
    note = (f"the pendulum leaves after one impact and does not return within the record: "
            f"it fixes omega_1, the trunk's damping ratio and its velocity after the impact "
            f"V_1 = m (1 + e) "
            f"u_1 / (M_T + m) (eqs 21, 54), not M_T and e apart; M_T, K_T, C_T and E are "
            f"ranges over e in [{intervals['restitution'][0]:.3g}, 1] (a smaller e fits the "
            f"record worse); a known e (--restitution) or a record of the pendulum (column y) "
            f"fixes them")
    return values, intervals, determined, note
