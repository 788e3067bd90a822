"""The contact pad's law: a spring-dashpot (k_c, c_c) and its restitution e and duration.

Design notes and measured figures: docs/contact-law.md.
"""

from __future__ import annotations

import functools
import math

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.options import Option
from treeimpact.analytic.model.parameters import DEFAULT_CONTACT_DURATION, Contact
from treeimpact.analytic.model.two_body import TwoBodyModel


def release_time(zeta: float) -> float:
    """Release time of one collision at damping ratio ``zeta`` (1), in units of 1/omega (see
    module docstring); ParameterError for zeta outside [0, inf)."""
    if zeta < 0 or not math.isfinite(zeta):
        raise ParameterError(f"zeta = {zeta!r}: allowed [0, inf)")
    if abs(zeta - 1.0) < 1e-9:
        return 2.0
    if zeta < 1.0:
        s = math.sqrt(1.0 - zeta * zeta)
        return (math.pi - math.atan2(2.0 * zeta * s, 1.0 - 2.0 * zeta * zeta)) / s
    sd = math.sqrt(zeta * zeta - 1.0)
    r1, r2 = -1.0 / (zeta + sd), -zeta - sd  # r1 r2 = 1: no cancellation in r1
    return 2.0 * math.log(r2 / r1) / (r1 - r2)


def restitution_for_damping_ratio(zeta: float) -> float:
    """e of one collision under F = max(0, k delta + c delta') with damping ratio zeta."""
    t = release_time(zeta)
    if abs(zeta - 1.0) < 1e-9:
        return math.exp(-t) * (t - 1.0)
    if zeta < 1.0:
        s = math.sqrt(1.0 - zeta * zeta)
        ex = math.exp(-zeta * t)
        return -ex * (math.cos(s * t) - zeta / s * math.sin(s * t))
    sd = math.sqrt(zeta * zeta - 1.0)
    r1, r2 = -1.0 / (zeta + sd), -zeta - sd
    return -(r1 * math.exp(r1 * t) - r2 * math.exp(r2 * t)) / (r1 - r2)


#: The smallest restitution a spring-dashpot contact is asked for (damping ratio ~50).
MIN_SOFT_RESTITUTION = 1e-4


def damping_ratio_for_restitution(e: float) -> float:
    """Inverse of :func:`restitution_for_damping_ratio` for 0 < e <= 1 (each e solved once
    a process: a run asks for its e two to three times, ~0.1 ms each by brentq)."""
    if isinstance(e, bool) or not isinstance(e, (int, float)) or not (
            MIN_SOFT_RESTITUTION <= e <= 1.0):
        raise ParameterError(
            f"contact.restitution = {e!r} is out of range for a soft contact: allowed "
            f"[{MIN_SOFT_RESTITUTION:g}, 1] (e = 0 needs infinite damping; e ~ 1 / (4 zeta^2) "
            "when overdamped, so 1e-4 already needs a damping ratio of 50)")
    return _damping_ratio(float(e))


@functools.lru_cache(maxsize=256)
def _damping_ratio(e: float) -> float:
    """:func:`damping_ratio_for_restitution` of a checked e (a pure function of e: kept)."""
    if e == 1.0:
        return 0.0
    hi = 1.0
    while restitution_for_damping_ratio(hi) > e:
        hi *= 2.0
    # lazy: +535 ms at import otherwise (scipy.optimize)
    from scipy.optimize import brentq

    return brentq(lambda z: restitution_for_damping_ratio(z) - e, 0.0, hi, xtol=1e-15,
                  rtol=1e-14)


def stiffness_for_duration(reduced_mass: float, duration: float) -> float:
    """k_c (N/m) whose undamped collision of ``reduced_mass`` mu (kg) lasts ``duration``
    (s): mu (pi / t)^2, the inverse of t = pi sqrt(mu / k_c)."""
    return reduced_mass * (math.pi / duration) ** 2


def contact_law(model: TwoBodyModel, contact: Contact | None = None, *,
                stiffness: float | None = None, duration: float | None = None
                ) -> tuple[float, float]:
    """(k_c in N/m, c_c in N s/m) giving the model's restitution e in one collision.

    The stiffness comes from ``stiffness`` or ``duration`` (keyword first, then the
    contact's), duration meaning the undamped collision time pi sqrt(mu / k); the default
    duration is :data:`analytic.model.parameters.DEFAULT_CONTACT_DURATION`.
    """
    mu = model.reduced_mass
    if stiffness is None and duration is None and contact is not None:
        stiffness, duration = contact.stiffness, contact.duration  # checked by the Contact
    else:  # a pad given here: checked as a Contact's fields (one of the two at most)
        Contact(restitution=model.restitution, stiffness=stiffness, duration=duration)
    if stiffness is None:
        stiffness = stiffness_for_duration(
            mu, DEFAULT_CONTACT_DURATION if duration is None else duration)
    zeta = damping_ratio_for_restitution(model.restitution)
    return stiffness, 2.0 * zeta * math.sqrt(stiffness * mu)


#: How a trunk other than the SDOF gets its contact damping: "pad" keeps the SDOF rung's
#: (k_c, c_c), one physical pad for every trunk; "effective" recalibrates c_c so that one
#: free collision with the trunk's instantaneous effective mass at the clamp rebounds at e
#: (the restitution convention; docs/contact-law.md).
CALIBRATIONS = ("pad", "effective")
CALIBRATION = Option(CALIBRATIONS, "the contact damping of a non-SDOF trunk: the SDOF's pad "
                     "(pad) or recalibrated so that e holds on its effective mass at the clamp "
                     "(effective)")


def pad_restitution(stiffness: float, damping: float, reduced_mass: float) -> float:
    """e of one free collision of ``reduced_mass`` mu (kg) under the pad (``stiffness`` k
    N/m, ``damping`` c N s/m).

    The pad's own e on a light trunk is smaller than on M_T (the same c is more damping
    there); below :data:`MIN_SOFT_RESTITUTION` it is refused with a one-line error.
    """
    e = restitution_for_damping_ratio(damping / (2.0 * math.sqrt(stiffness * reduced_mass)))
    if e < MIN_SOFT_RESTITUTION:
        raise ParameterError(
            f"contact.restitution: the pad rebounds at e = {e:.3g} on the trunk's effective "
            f"mass, below {MIN_SOFT_RESTITUTION:g}: a larger e or --calibration effective")
    return e


def effective_damping(stiffness: float, restitution: float, reduced_mass: float) -> float:
    """c_c (N s/m) giving ``restitution`` e in one free collision of ``reduced_mass`` mu
    (kg) at ``stiffness`` k (N/m): 2 zeta(e) sqrt(k mu)."""
    zeta = damping_ratio_for_restitution(restitution)
    return 2.0 * zeta * math.sqrt(stiffness * reduced_mass)


def pad_fields(stiffness: float | None, damping: float | None,
               reduced_mass: float | None) -> dict:
    """What the pad is against the mass it strikes (a backend's model dict): the
    ``reduced_mass`` mu (kg) of the pendulum and the trunk's instantaneous effective mass at
    the clamp, and the pad's damping ratio c_c / (2 sqrt(k_c mu)) there from its
    ``stiffness`` k_c (N/m) and ``damping`` c_c (N s/m) (1; above 1 the pad is overdamped
    against the clamp and rebounds at far less than its nominal e). None where unknown."""
    if not (stiffness and reduced_mass) or damping is None:
        return {"contact_reduced_mass": reduced_mass, "pad_damping_ratio": None}
    return {"contact_reduced_mass": reduced_mass,
            "pad_damping_ratio": damping / (2.0 * math.sqrt(stiffness * reduced_mass))}


def collision_duration(model: TwoBodyModel, stiffness: float, damping: float) -> float:
    """Duration (s) of one free two-body collision under the law (``stiffness`` k_c N/m,
    ``damping`` c_c N s/m) on ``model``'s reduced mass, first touch to release."""
    mu = model.reduced_mass
    omega = math.sqrt(stiffness / mu)
    return release_time(damping / (2.0 * math.sqrt(stiffness * mu))) / omega


def detection_duration(model, contact=None, *, stiffness: float | None = None) -> float:
    """Free-collision duration (s) on which impacts are told from moving together: the SDOF
    two-body model's collision under the contact law for the model's e (stiffness N/m from
    ``stiffness``, else the contact's stiffness or duration), whatever trunk the backend has."""
    return collision_duration(model, *contact_law(model, contact, stiffness=stiffness))
