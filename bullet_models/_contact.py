"""How Bullet turns a contact stiffness and damping into ERP/CFM, and the time-step correction.

Design notes and measured figures: docs/contact-law.md.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

from scipy.optimize import brentq

from treeimpact.analytic.contact.law import (
    damping_ratio_for_restitution,
    restitution_for_damping_ratio,
)
from treeimpact.analytic.errors import ParameterError

MAX_COLLISION_STEPS = 1_000_000  # guard: a collision longer than this many steps is a bug


def combine_stiffness(k0: float, k1: float) -> float:
    """Bullet's combined contact stiffness of two colliders (series), N/m."""
    return 1.0 / (1.0 / k0 + 1.0 / k1)


def combine_damping(d0: float, d1: float) -> float:
    """Bullet's combined contact damping of two colliders (sum), N s/m."""
    return d0 + d1


def per_body(k: float, c: float) -> tuple[float, float]:
    """(stiffness, damping) to give each of the two contacting links so they combine to (k, c)."""
    return 2.0 * k, 0.5 * c


def erp_cfm(k: float, c: float, dt: float) -> tuple[float, float]:
    """Bullet's (ERP, CFM) of a contact with stiffness k (N/m) and damping c (N s/m) at step dt (s).

    CFM is returned as Bullet stores it before dividing by dt: 1 / (dt k + c), s/kg... per dt.
    """
    den = dt * k + c
    return dt * k / den, 1.0 / den


def discrete_collision(k: float, c: float, mu: float, dt: float, v0: float = 1.0):
    """Replay one collision of two free bodies under Bullet's update (module docstring).

    Starts touching (overlap 0) with approach velocity ``v0`` (m/s); returns
    ``(e, steps, impulses)``: the rebound ratio, the steps with a positive impulse and the
    impulses (N s) per step, ending once the bodies separate.
    """
    erp, cfm = erp_cfm(k, c, dt)
    inv = 1.0 / (1.0 / mu + cfm / dt)
    delta, w = 0.0, v0
    impulses = []
    for _ in range(MAX_COLLISION_STEPS):
        rhs = w + (erp * delta / dt if delta >= 0.0 else delta / dt)
        lam = max(0.0, rhs * inv)
        w -= lam / mu
        delta += dt * w
        impulses.append(lam)
        if delta < 0.0 and w < 0.0:
            steps = sum(1 for p in impulses if p > 0.0)
            return -w / v0, steps, impulses
    raise ParameterError("--dt / --contact-stiffness: one free collision did not end "
                         f"within {MAX_COLLISION_STEPS} steps: a larger --dt or a softer contact")


@dataclass(frozen=True)
class BulletContact:
    """The soft contact as Bullet gets it (SI units)."""

    stiffness: float  # k_b, N/m: matched-pole stiffness (within a few % of the law's)
    damping: float  # c_b, N s/m: the law's damping less what the time step adds
    law_stiffness: float  # k, N/m: the continuous law's stiffness
    law_damping: float  # c, N s/m: the continuous law's damping
    reduced_mass: float  # mu, kg: the mass the correction was made for
    dt: float  # s
    restitution: float  # target e of one collision
    erp: float
    cfm: float  # 1 / (dt k + c_b), before Bullet divides by dt
    steps_per_collision: int  # steps with a positive impulse in the replayed collision

    @property
    def per_body(self) -> tuple[float, float]:
        return per_body(self.stiffness, self.damping)


def matched_pole(k: float, c: float, mu: float, dt: float) -> tuple[float, float]:
    """(k_b, c_b) whose backward-Euler step has the exact one-step decay and rotation of (k, c).

    The implicit step's roots z satisfy sigma = (1 - 1/z) / dt with sigma a root of
    mu sigma^2 + c_b sigma + k_b = 0; asking z = exp(s dt) for the roots s of the law
    mu s^2 + c s + k = 0 gives sigma_i = (1 - exp(-s_i dt)) / dt, hence
    k_b = mu sigma_1 sigma_2 and c_b = -mu (sigma_1 + sigma_2) (real for real k, c).
    """
    zeta = c / (2.0 * math.sqrt(k * mu))
    omega = math.sqrt(k / mu)
    disc = complex(zeta * zeta - 1.0) ** 0.5
    s1, s2 = omega * (-zeta + disc), omega * (-zeta - disc)
    sig1 = (1.0 - cmath.exp(-s1 * dt)) / dt
    sig2 = (1.0 - cmath.exp(-s2 * dt)) / dt
    return mu * (sig1 * sig2).real, -mu * (sig1 + sig2).real


def bullet_contact(k: float, c: float, mu: float, dt: float) -> BulletContact:
    """Bullet's (k_b, c_b) for the continuous law (k, c) between bodies of reduced mass mu, at dt.

    k_b from :func:`matched_pole` (the discrete contact oscillates and decays at the law's
    rates), then c_b tuned by Brent's method so that the replayed free collision
    (:func:`discrete_collision`) rebounds with exactly the law's e; c_b stays within a
    few per cent of the matched-pole damping, which alone leaves e off by up to 0.005.
    """
    zeta = c / (2.0 * math.sqrt(k * mu))
    target = restitution_for_damping_ratio(zeta)
    k_b, c_pole = matched_pole(k, c, mu, dt)
    e_free, _, _ = discrete_collision(k_b, 0.0, mu, dt)
    if e_free < target:
        raise ParameterError(
            f"dt = {dt:.3g} s is too large for Bullet's soft contact at e = {target:.3g}: the "
            f"implicit step alone gives e = {e_free:.4g}; allowed dt <= "
            f"{largest_time_step(k, c, mu):.3g} s")
    if target >= 1.0 or e_free == target:
        c_b = 0.0
    else:
        hi = max(c_pole, c, 1e-12)
        while discrete_collision(k_b, hi, mu, dt)[0] > target:
            hi *= 2.0
        c_b = brentq(lambda cb: discrete_collision(k_b, cb, mu, dt)[0] - target, 0.0, hi,
                     xtol=1e-12 * hi, rtol=1e-12)
    erp, cfm = erp_cfm(k_b, c_b, dt)
    steps = discrete_collision(k_b, c_b, mu, dt)[1]
    return BulletContact(stiffness=k_b, damping=c_b, law_stiffness=k, law_damping=c,
                         reduced_mass=mu, dt=dt, restitution=target, erp=erp, cfm=cfm,
                         steps_per_collision=steps)


def largest_time_step(k: float, c: float, mu: float) -> float:
    """Largest dt (s) at which c_b >= 0 exists: the undamped implicit collision keeps e >= target."""
    target = restitution_for_damping_ratio(c / (2.0 * math.sqrt(k * mu)))
    omega = math.sqrt(k / mu)
    if target >= 1.0:
        return 0.0

    def feasible(dt):
        return discrete_collision(matched_pole(k, c, mu, dt)[0], 0.0, mu, dt)[0] >= target

    lo, hi = 1e-6 / omega, 1.0 / omega
    if feasible(hi):
        return hi
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        if feasible(mid):
            lo = mid
        else:
            hi = mid
    return lo


def law_for_restitution(e: float, k: float, mu: float) -> float:
    """Damping c (N s/m) of the continuous law F = max(0, k delta + c delta') giving e."""
    return 2.0 * damping_ratio_for_restitution(e) * math.sqrt(k * mu)
