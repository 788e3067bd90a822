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
from treeimpact.analytic.results import FreeCollision

from .options import INTEGRATORS

#: Integrators that take a free collision with Euler's map (module docstring).
EULER_CONTACT_MAP = ("Euler", "implicit", "implicitfast")
IMPEDANCE = 1e-4  # d: MuJoCo's mjMINIMP, the smallest impedance it accepts (see docstring)
SOLIMP_TAIL = (0.001, 0.5, 2.0)  # width, midpoint, power: unused when dmin == dmax
MAX_COLLISION_STEPS = 1_000_000  # guard: a longer collision is a bad (k, c, h)


def effective_denominator(inverse_mass: float, inverse_mass_approx: float,
                          impedance: float = IMPEDANCE) -> float:
    """S = d A + (1 - d) A_hat (1/kg) of a contact row, MuJoCo's force being
    (k' delta + b' delta') / S (docs/contact-law.md): ``inverse_mass`` A = J M^-1 J^T (1/kg,
    the exact inverse effective mass at the contact), ``inverse_mass_approx`` A_hat (1/kg,
    MuJoCo's efc_diagApprox: the two bodies' body_invweight0) and the constant
    ``impedance`` d (1, :data:`IMPEDANCE` by default)."""
    return impedance * inverse_mass + (1.0 - impedance) * inverse_mass_approx


def solref_for_law(k: float, c: float, denominator: float) -> tuple[float, float]:
    """Direct ``solref`` (-k S, -c S) (1/s^2, 1/s) giving the law F = k delta + c delta' of
    stiffness ``k`` (N/m) and damping ``c`` (N s/m), S the row's ``denominator`` (1/kg,
    :func:`effective_denominator`)."""
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
    """The (k_d, c_d) MuJoCo needs so that one free collision of reduced mass ``mu`` (kg)
    rebounds at the restitution ``e`` (1), as an :class:`EngineLaw`.

    ``k`` (N/m) is the continuous law's stiffness; c = 2 zeta(e) sqrt(k mu) its damping
    (:func:`analytic.contact.law.damping_ratio_for_restitution`); ``h`` (s) the time step and
    ``integrator`` MuJoCo's (one of :data:`.options.INTEGRATORS`). For the integrators with
    Euler's contact map, pole matching and Brent's method on c_d; for RK4 (k, c) unchanged,
    its own restitution replayed (docs/contact-law.md). A one-line ParameterError for an
    unknown integrator or a k, mu or h not in (0, inf).
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


def time_constant_solref(k: float, c: float, denominator: float) -> tuple[float, float]:
    """The positive ``solref = (timeconst, dampratio)`` equal to the direct one of
    :func:`solref_for_law` for the law (``k`` N/m, ``c`` N s/m) and the row's
    ``denominator`` S (1/kg, :func:`effective_denominator`): with a constant impedance MuJoCo
    takes k' = 1 / (timeconst^2 dampratio^2) and b' = 2 / timeconst, so timeconst =
    2 / (c S) (s) and dampratio = c S / (2 sqrt(k S)) (1). MuJoCo raises a timeconst below
    2 dt to 2 dt unless the ``refsafe`` flag is disabled. A one-line ParameterError unless
    k S > 0 and c S > 0."""
    ks, cs = k * denominator, c * denominator
    if not (ks > 0 and cs > 0):
        raise ParameterError(f"contact (k, c) = ({k:.4g}, {c:.4g}): the time-constant solref "
                             "needs k > 0 and c > 0")
    return 2.0 / cs, cs / (2.0 * math.sqrt(ks))


MINVAL = 1e-15  # MuJoCo's mjMINVAL: it computes K = 1 / max(MINVAL, d^2 timeconst^2 dampratio^2)


def time_constant_impedance(k: float, denominator: float) -> float:
    """The constant impedance d (1) for a time-constant solref of stiffness ``k`` (N/m) on a
    row of ``denominator`` S (1/kg, :func:`effective_denominator`): MuJoCo caps
    k' = 1 / (timeconst dampratio)^2 at d^2 / MINVAL (measured: 1e7 at d = 1e-4), so d is
    :data:`IMPEDANCE` or, for a stiffer law, sqrt(10 k S MINVAL) (a tenth of the cap)."""
    return max(IMPEDANCE, math.sqrt(10.0 * k * denominator * MINVAL))


#: Radius (m) of the spheres of :func:`two_body_mjcf` (geometry only).
SPHERE_RADIUS = 0.05


def two_body_mjcf(mass: float, other_mass: float, dt: float, solref, solimp,
                  refsafe: bool = True) -> str:
    """A plain MJCF (text): sphere ``a`` (``mass``, kg, free joint) touching sphere ``b``
    (``other_mass``, kg, free joint; fixed in the world when infinite) along x, no gravity,
    Euler at ``dt`` (s); the only contact is the pair ``impact`` (condim 1, margin 0) with
    ``solref``/``solimp``. ``refsafe`` False disables MuJoCo's refsafe flag (which raises a
    time-constant solref's timeconst below 2 dt to 2 dt)."""
    # lazy: +62 ms at import otherwise (mujoco)
    import mujoco

    spec = mujoco.MjSpec()
    spec.modelname = "two-body-collision"
    spec.option.timestep = dt
    spec.option.gravity = [0.0, 0.0, 0.0]
    if not refsafe:
        spec.option.disableflags = int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)
    for name, m, x in (("a", mass, -SPHERE_RADIUS), ("b", other_mass, SPHERE_RADIUS)):
        parent = spec.worldbody
        if math.isfinite(m):
            parent = spec.worldbody.add_body()
            parent.name = name
            parent.pos = [x, 0.0, 0.0]
            parent.explicitinertial = True
            parent.mass = m
            parent.inertia = [0.4 * m * SPHERE_RADIUS ** 2] * 3
            parent.add_freejoint()
        g = parent.add_geom()
        g.name = name
        g.type = mujoco.mjtGeom.mjGEOM_SPHERE
        g.size = [SPHERE_RADIUS, 0.0, 0.0]
        g.contype = 0
        g.conaffinity = 0
        if not math.isfinite(m):
            g.pos = [x, 0.0, 0.0]
    add_impact_pair(spec, "a", "b", solref, solimp)
    return spec.to_xml()


def add_impact_pair(spec, geom1: str, geom2: str, solref, solimp):
    """The only contact of every model here: the pair ``impact`` between ``geom1`` and
    ``geom2``, frictionless (condim 1), no margin or gap, with ``solref`` and ``solimp``."""
    pair = spec.add_pair()
    pair.name = "impact"
    pair.geomname1 = geom1
    pair.geomname2 = geom2
    pair.condim = 1
    pair.margin = 0.0
    pair.gap = 0.0
    pair.solref = list(solref)
    pair.solimp = list(solimp)
    return pair


def two_body_collision(xml: str, speed: float = 1.0, overlap: float = 1e-12
                       ) -> FreeCollision:
    """Collide body ``a`` of a :func:`two_body_mjcf`-like model (its MJCF text ``xml``) into
    ``b`` at ``speed`` (m/s), starting touching (``overlap`` m, as the replay of
    :func:`discrete_collision`): its :class:`analytic.results.FreeCollision` (restitution
    NaN where the state left the finite: a step too large for the law). The duration ends
    where the pair's law force (k' delta + b' delta') / S, evaluated on the engine's states
    (delta from the spheres' centres), first reaches zero, interpolated between the steps it
    acts over (Euler: the force of state n acts over step n, from n dt); MuJoCo's warnings
    told on stderr (:func:`mujoco_models._warnings.mujoco_warnings`)."""
    # lazy: +37 ms at import otherwise (treeimpact.mujoco_models._warnings)
    from ._warnings import mujoco_warnings

    with mujoco_warnings():
        return _collide(xml, speed, overlap)


def _collide(xml: str, speed: float, overlap: float) -> FreeCollision:
    """:func:`two_body_collision` without its warning handler."""
    # lazy: +38 ms at import otherwise (mujoco)
    import mujoco

    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    a = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "a")
    b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "b")
    d.qpos[m.jnt_qposadr[m.body_jntadr[a]]] += overlap
    d.qvel[m.jnt_dofadr[m.body_jntadr[a]]] = speed
    b_moves = b >= 0 and m.body_jntadr[b] >= 0  # else b is a geom of the world
    ga, gb = (mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, g) for g in ("a", "b"))
    reach = m.geom_size[ga, 0] + m.geom_size[gb, 0]
    pair = 0
    kd, cd = -m.pair_solref[pair, 0], -m.pair_solref[pair, 1]  # k' and b' (direct solref)
    if m.pair_solref[pair, 0] > 0:  # time-constant solref: k' = 1 / (tc dr)^2, b' = 2 / tc
        tc, dr = m.pair_solref[pair]
        kd, cd = 1.0 / (tc * dr) ** 2, 2.0 / tc

    def state():
        mujoco.mj_kinematics(m, d)
        va = d.qvel[m.jnt_dofadr[m.body_jntadr[a]]]
        vb = d.qvel[m.jnt_dofadr[m.body_jntadr[b]]] if b_moves else 0.0
        delta = reach - (d.geom_xpos[gb, 0] - d.geom_xpos[ga, 0])
        return kd * delta + cd * (va - vb), vb - va

    law_prev, _ = state()
    pushing, steps, t_release, peak = 0, 0, None, 0.0
    while steps < MAX_COLLISION_STEPS:
        mujoco.mj_step(m, d)
        steps += 1
        if d.ncon and float(np.sum(d.efc_force[:d.nefc])) > 0.0:
            pushing += 1
        law, sep = state()
        if not (math.isfinite(law) and math.isfinite(sep)) or d.time < steps * m.opt.timestep \
                * (1 - 1e-9):  # blew up (MuJoCo resets a non-finite state and warns)
            return FreeCollision(math.nan, math.nan, pushing, math.nan)
        peak = max(peak, reach - (d.geom_xpos[gb, 0] - d.geom_xpos[ga, 0]))
        if t_release is None and law <= 0.0:
            t_release = (steps - 1 + law_prev / (law_prev - law)) * m.opt.timestep
        if t_release is not None and sep > 0.0:
            return FreeCollision(sep / speed, t_release, pushing, peak)
        law_prev = law
    raise ParameterError("--dt: the collision did not end within "
                         f"{MAX_COLLISION_STEPS} steps")
