"""MuJoCo's soft contact as a spring-dashpot, and the restitution-to-damping mapping.

What MuJoCo 3.3.7 integrates (read in ``engine_core_constraint.c``, ``engine_solver.c``,
``engine_forward.c``)
--------------------------------------------------------------------------------------
One frictionless contact (``condim 1``) is one inequality row with Jacobian J (relative
normal velocity, > 0 separating), distance r = efc_pos (< 0 when overlapping, margin 0)
and velocity v = J qvel. ``mj_makeImpedance`` sets, for a *direct* ``solref = (-k', -b')``
and an impedance ``d`` that is constant when ``solimp[0] == solimp[1]`` (``getimpedance``
returns the flat value), K = k' / d^2, B = b' / d, R = (1 - d) / d * A_hat, and
``mj_referenceConstraint`` the reference acceleration aref = -B v - K d r. A_hat is
``efc_diagApprox``, for a contact the sum of the two bodies' translational
``body_invweight0`` (``mj_diagApprox``; computed once at qpos0 by ``mj_setConst``: 1/mass for
a body on slide joints, a third of the trace of the centre-of-mass inverse inertia
otherwise). The solver minimises the Gauss cost plus (1/2R) (J qacc - aref)^2 on the active
side, so the row's force is

    f = max(0, (aref - a0) / (A + R)) = max(0, (k' delta + b' delta' - d a0) / S),
    S = d A + (1 - d) A_hat,

with delta = -r the overlap, A = J M^-1 J^T the exact inverse effective mass and a0 = J
qacc_smooth the relative acceleration the other forces give. So MuJoCo's contact is a
spring-dashpot F = max(0, k delta + c delta') -- pushing only, released when the *force*
reaches zero, the law of :mod:`analytic.soft_contact` -- with k = k'/S and c = b'/S, plus a
term -d a0 / S that a spring-dashpot does not have (it makes the contact also cancel the
bodies' other relative acceleration). We take d at MuJoCo's smallest impedance
:data:`IMPEDANCE` = mjMINIMP = 1e-4 (``solimp = "1e-4 1e-4 ..."``): the extra term is then
1e-4 of the load and S is within 1e-4 A of A_hat, a constant of the compiled model, so
``solref = (-k S, -c S)`` gives the law (k, c). (The opposite choice d -> 1, e.g. solimp
0.99, makes the contact a kinematic constraint delta'' = -B delta' - K delta whatever the
load: no longer a force law, and its release depends on the other forces.) The contact
exists while the distance is <= 0 (``mjraw_SphereSphere``: no contact when the centres are
farther than the radii sum plus the margin, 0 here), so F = 0 for delta < 0.

Time stepping. The Euler integrator is semi-implicit: v_{n+1} = v_n + h qacc(q_n, v_n),
q_{n+1} = q_n + h v_{n+1}; the contact force is explicit in (delta_n, delta'_n). For two
free bodies of reduced mass mu = 1/A the relative motion is the linear map

    w_{n+1} = w_n - h (k delta_n + c w_n) / mu,    delta_{n+1} = delta_n + h w_{n+1}

(w = delta') while the force is positive, and free flight afterwards: after the first step
with k delta_n + c w_n <= 0 the separation speed never changes again (delta falls, so the
law stays negative). :func:`discrete_collision` replays this in closed form (eigenvalues of
the 2x2 map). Its restitution differs from the continuous e(zeta) at O(omega h): the
explicit damping step has determinant 1 - h c / mu instead of exp(-h c / mu). The mapping
(:func:`engine_law`) therefore takes (k, c) of the continuous law of the target e
(:func:`analytic.soft_contact.contact_law`), matches the poles of the map to the law's
(:func:`matched_pole`: exact one-step decay and rotation), and then tunes c by Brent's
method until the replayed free collision rebounds with exactly the target e; the tests
check the replay against MuJoCo itself (SDOF and chain trunks, 0.05 <= e <= 0.9).

Other integrators (``integrator``, :data:`INTEGRATORS`; read in ``engine_forward.c``).
``implicit`` and ``implicitfast`` solve (M - h qDeriv) qacc = qfrc_smooth + qfrc_constraint
and then take the same step as Euler (``mj_advance``: velocity first, the position with
the new velocity). qDeriv holds velocity derivatives of the *smooth* forces only (joint and
tendon dampers; ``implicit`` adds the Coriolis terms): the contact is a constraint force,
explicit in (delta_n, w_n) exactly as under Euler. A free collision therefore follows the
same map, and the Euler correction above is exact for them too (measured: the same e as
Euler to round-off, except ``implicit`` on the free chain, within 7e-6: its linearised
Coriolis forces). ``RK4`` (``mj_RungeKutta``) is the classical four-stage method:
every stage recomputes the contact (detection included) at its own state, so the force
enters at four points per step and the map is not the one above: Euler's correction
would make it miss e by as much as Euler misses it uncorrected (+0.0104 at e = 0.3 and
the default step, measured). For RK4 the engine gets the continuous law (k, c)
*uncorrected* (``stiffness = law_stiffness``, ``damping = law_damping``): RK4 is
consistent at high order, so the restitution it gives converges to the law's e as dt -> 0
and what remains is RK4's own error, which a speed-accuracy curve is meant to show.
:func:`discrete_collision_rk4` replays that free collision (``uncorrected_restitution``
and ``steps_per_collision`` of the law; it matches MuJoCo to 1e-9). Measured on the SDOF
trunk at 50 steps per collision: |e - target| <= 9.4e-8 for 0.05 <= e <= 0.9, falling with
dt at order 3.2 to 4.1 between 25, 50 and 100 steps (the force's kink at release, inside
one step, keeps RK4 from a clean fourth order), down to the 1e-9 floor of the measurement.
RK4's larger error is elsewhere: a contact that *starts* inside a step (a re-contact, the
full pendulum's arrival) jumps to c w at once, and the stages weight that jump 1/6 to 5/6
of the step instead of the part of the step in contact, an O(h) error that the Euler map
does not have.
"""

from __future__ import annotations

import cmath
import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from analytic.parameters import ParameterError
from analytic.soft_contact import damping_ratio_for_restitution, restitution_for_damping_ratio

#: Values of the ``integrator`` option (MuJoCo's names, ``mjtIntegrator``).
INTEGRATORS = ("Euler", "implicit", "implicitfast", "RK4")
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
    raise ParameterError("discrete_collision: the bodies never separated (check k, c, dt)")


def _discrete_collision_loop(k, c, mu, h):
    delta, w = 0.0, 1.0
    for n in range(1, MAX_COLLISION_STEPS):
        w -= h * (k * delta + c * w) / mu
        delta += h * w
        if k * delta + c * w <= 0.0 or delta < 0.0:
            return -w, n
    raise ParameterError("discrete_collision: the bodies never separated (check k, c, dt)")


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
    raise ParameterError("discrete_collision_rk4: the bodies never separated (check k, c, dt)")


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
    (:func:`analytic.soft_contact.damping_ratio_for_restitution`); then, for the integrators
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
    """e of the continuous law (k, c) for reduced mass mu (analytic.soft_contact)."""
    return restitution_for_damping_ratio(c / (2.0 * math.sqrt(k * mu)))
