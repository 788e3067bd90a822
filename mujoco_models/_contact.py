"""MuJoCo's soft contact as a spring-dashpot, and the restitution-to-damping mapping.

Design notes and measured figures: docs/contact-law.md.
"""

from __future__ import annotations

import cmath
import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from treeimpact.analytic.contact.law import (
    damping_ratio_for_restitution,
    restitution_for_damping_ratio,
)
from treeimpact.analytic.errors import ParameterError

from .options import INTEGRATORS

#: Integrators that take a free collision with Euler's map (module docstring).
EULER_CONTACT_MAP = ("Euler", "implicit", "implicitfast")
IMPEDANCE = 1e-4  # d: MuJoCo's mjMINIMP, the smallest impedance it accepts (see docstring)
SOLIMP_TAIL = (0.001, 0.5, 2.0)  # width, midpoint, power: unused when dmin == dmax
MAX_COLLISION_STEPS = 1_000_000  # guard: a longer collision is a bad (k, c, h)


def effective_denominator(inverse_mass: float, inverse_mass_approx: float,
                          impedance: float = IMPEDANCE) -> float:
    """S = d A + (1 - d) A_hat (1/kg): MuJoCo's force is (k' delta + b' delta') / S."""
    return impedance * inverse_mass + (1.0 - impedance) * inverse_mass_approx


def solref_for_law(k: float, c: float, denominator: float) -> tuple[float, float]:
    """Direct ``solref`` (-k S, -c S) giving the law F = k delta + c delta' (N/m, N s/m)."""
    return -k * denominator, -c * denominator


def discrete_collision(k: float, c: float, mu: float, h: float) -> tuple[float, int]:
    """One free collision under MuJoCo's Euler step (module docstring); (e, contact steps).

    Starts touching (delta_0 = 0, the contact active) with unit approach speed. Closed form:
    the state (delta_n, w_n) = V diag(z^n) V^-1 (0, 1) with z the eigenvalues of the map.
    """
    a = h * h * k / mu
    b = h * c / mu
    A = np.array([[1.0 - a, h * (1.0 - b)], [-h * k / mu, 1.0 - b]])
    z, V = np.linalg.eig(A.astype(complex))
    if abs(z[0] - z[1]) < 1e-9 * max(abs(z[0]), 1e-300):
        return _discrete_collision_loop(k, c, mu, h)
    coef = np.linalg.solve(V, np.array([0.0, 1.0], dtype=complex))
    n = 1
    chunk = 256
    while n < MAX_COLLISION_STEPS:
        idx = np.arange(n, n + chunk)
        zn = z[None, :] ** idx[:, None]
        s = (zn * coef[None, :]) @ V.T
        delta, w = s[:, 0].real, s[:, 1].real
        stop = np.flatnonzero((k * delta + c * w <= 0.0) | (delta < 0.0))
        if stop.size:
            i = int(stop[0])
            return float(-w[i]), int(n + i)
        n += chunk
        chunk *= 2
    raise ParameterError("--dt / --contact-stiffness: one free collision did not end "
                         f"within {MAX_COLLISION_STEPS} steps: a larger --dt or a softer contact")


def _discrete_collision_loop(k, c, mu, h):
    delta, w = 0.0, 1.0
    for n in range(1, MAX_COLLISION_STEPS):
        w -= h * (k * delta + c * w) / mu
        delta += h * w
        if k * delta + c * w <= 0.0 or delta < 0.0:
            return -w, n
    raise ParameterError("--dt / --contact-stiffness: one free collision did not end "
                         f"within {MAX_COLLISION_STEPS} steps: a larger --dt or a softer contact")


def discrete_collision_rk4(k: float, c: float, mu: float, h: float) -> tuple[float, int]:
    """One free collision under MuJoCo's RK4 step (module docstring); (e, contact steps).

    Starts touching (delta_0 = 0) with unit approach speed. Each stage evaluates the force
    max(0, k delta + c w) at its own state, and none while the stage is apart (delta < 0:
    MuJoCo detects no contact); the result is the first state whose force is zero, as for
    :func:`discrete_collision`.
    """
    def rate(delta, w):
        f = max(0.0, k * delta + c * w) if delta >= 0.0 else 0.0
        return w, -f / mu

    delta, w = 0.0, 1.0
    for n in range(1, MAX_COLLISION_STEPS):
        d1, w1 = rate(delta, w)
        d2, w2 = rate(delta + 0.5 * h * d1, w + 0.5 * h * w1)
        d3, w3 = rate(delta + 0.5 * h * d2, w + 0.5 * h * w2)
        d4, w4 = rate(delta + h * d3, w + h * w3)
        delta += h / 6.0 * (d1 + 2.0 * d2 + 2.0 * d3 + d4)
        w += h / 6.0 * (w1 + 2.0 * w2 + 2.0 * w3 + w4)
        if k * delta + c * w <= 0.0 or delta < 0.0:
            return -w, n
    raise ParameterError("--dt / --contact-stiffness: one free collision did not end "
                         f"within {MAX_COLLISION_STEPS} steps (RK4): a larger --dt or a softer contact")


def matched_pole(k: float, c: float, mu: float, h: float) -> tuple[float, float]:
    """(k_d, c_d) whose Euler map has the eigenvalues exp(s h) of the law's roots s.

    The map has determinant 1 - h c_d / mu and trace 2 - h c_d / mu - h^2 k_d / mu; the law
    mu s^2 + c s + k = 0 has exp(s1 h) exp(s2 h) = exp(-h c / mu).
    """
    zeta = c / (2.0 * math.sqrt(k * mu))
    omega = math.sqrt(k / mu)
    disc = complex(zeta * zeta - 1.0) ** 0.5
    s1, s2 = omega * (-zeta + disc), omega * (-zeta - disc)
    trace = (cmath.exp(s1 * h) + cmath.exp(s2 * h)).real
    det = math.exp(-h * c / mu)
    c_d = mu * (1.0 - det) / h
    k_d = mu * (1.0 + det - trace) / (h * h)
    return k_d, c_d


@dataclass(frozen=True)
class EngineLaw:
    """The contact law MuJoCo gets (SI units) and where it comes from."""

    stiffness: float  # k_d, N/m: given to MuJoCo (matched pole)
    damping: float  # c_d, N s/m: given to MuJoCo (tuned: exact e in the replay)
    law_stiffness: float  # k, N/m: continuous law
    law_damping: float  # c, N s/m: continuous law for the same mu and e
    reduced_mass: float  # mu, kg: 1 / A at the contact configuration
    dt: float  # s
    restitution: float  # target e of one free collision
    steps_per_collision: int  # steps with a positive force in the replayed collision
    uncorrected_restitution: float  # e of the replay with the continuous (k, c): the O(h) error
    integrator: str = "Euler"  # the replay's integrator; RK4 gets (k, c) uncorrected


@functools.lru_cache(maxsize=1024)
def engine_law(k: float, e: float, mu: float, h: float, integrator: str = "Euler") -> EngineLaw:
    """The (k_d, c_d) MuJoCo needs so that one free collision of reduced mass mu rebounds at e.

    k (N/m) is the continuous law's stiffness; c = 2 zeta(e) sqrt(k mu) its damping
    (:func:`analytic.contact.law.damping_ratio_for_restitution`); then, for the integrators
    with Euler's contact map, pole matching and Brent's method on c_d; for RK4 (k, c)
    unchanged, its own restitution replayed (module docstring).
    """
    if integrator not in INTEGRATORS:
        raise ParameterError(f"--integrator = {integrator!r}: allowed {', '.join(INTEGRATORS)}")
    for name, v in (("contact stiffness", k), ("reduced mass", mu), ("dt", h)):
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(f"{name} = {v!r}: allowed (0, inf)")
    zeta = damping_ratio_for_restitution(e)
    c = 2.0 * zeta * math.sqrt(k * mu)
    if integrator not in EULER_CONTACT_MAP:  # RK4: the continuous law, its own error
        e_rk4, steps = discrete_collision_rk4(k, c, mu, h)
        return EngineLaw(stiffness=k, damping=c, law_stiffness=k, law_damping=c,
                         reduced_mass=mu, dt=h, restitution=e, steps_per_collision=steps,
                         uncorrected_restitution=e_rk4, integrator=integrator)
    k_d, c_pole = matched_pole(k, c, mu, h)
    e_raw = discrete_collision(k, c, mu, h)[0]
    e_free = discrete_collision(k_d, 0.0, mu, h)[0]
    if e_free < e:  # pragma: no cover - Euler's undamped collision rebounds at e ~ 1
        raise ParameterError(f"dt = {h:.3g} s: MuJoCo's undamped collision gives e = "
                             f"{e_free:.4g} < target {e:.4g}")
    if e >= 1.0:
        c_d = 0.0
    else:
        hi = mu / h * (1.0 - 1e-12)  # c_d h / mu = 1 stops the bodies in one step: e = 0
        c_d = brentq(lambda cd: discrete_collision(k_d, cd, mu, h)[0] - e, 0.0, hi,
                     xtol=1e-13 * max(c_pole, 1.0), rtol=1e-13)
    steps = discrete_collision(k_d, c_d, mu, h)[1]
    return EngineLaw(stiffness=k_d, damping=c_d, law_stiffness=k, law_damping=c,
                     reduced_mass=mu, dt=h, restitution=e, steps_per_collision=steps,
                     uncorrected_restitution=e_raw, integrator=integrator)


def law_restitution(k: float, c: float, mu: float) -> float:
    """e of the continuous law (k, c) for reduced mass mu (analytic.contact.soft)."""
    return restitution_for_damping_ratio(c / (2.0 * math.sqrt(k * mu)))
