"""MuJoCo and Bullet contact settings for a target restitution and touch duration (or the
pad's stiffness and damping) at a time step, each checked by simulating the two-body
collision in its engine: what ``treeimpact contact`` prints. SI units; design notes:
docs/contact-settings.md.

Each engine is asked on its own: an engine that cannot hold the step answers with the
largest step it can (``{"error": ..., "largest_dt": ...}``) and the other's settings stand.
"""

from __future__ import annotations

import math

from treeimpact.analytic.contact.law import (
    damping_ratio_for_restitution,
    release_time,
    restitution_for_damping_ratio,
)
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import check_range

from .backends import ENGINE_REGISTRY
from .backends import engines as registered_engines
from .backends import quiet_stdout
from .contact_engines import SPEED

#: Fewest steps of the target collision the command accepts (0.5e5 steps per collision at
#: most keep the two simulations under a second).
MAX_STEPS_PER_COLLISION = 50_000
#: The registered engines that give contact settings (their registration's ``contact``),
#: in the order they print.
ENGINES = registered_engines(contact=True)
#: Allowed ranges (SI): a milligram to a thousand tonnes, the pad's stiffness and damping,
#: the touch duration; beyond them the arithmetic leaves double precision.
MASS_RANGE = (1e-6, 1e9)
STIFFNESS_RANGE = (1e-3, 1e15)
DAMPING_RANGE = (1e-9, 1e12)
TOUCH_DURATION_RANGE = (1e-9, 10.0)


def masses(mass, other_mass, effective_mass) -> tuple[float, float]:
    """(m1, m2) in kg from ``mass`` and ``other_mass`` (None or inf: a fixed body);
    ``effective_mass`` mu is m1 = mu, m2 fixed. Raises ParameterError naming the flag out
    of :data:`MASS_RANGE`."""
    low, high = MASS_RANGE
    if effective_mass is not None:
        if mass is not None or other_mass is not None:
            raise ParameterError("--effective-mass: give it instead of --mass/--other-mass")
        return check_range("--effective-mass", effective_mass, low=low, high=high,
                           unit="kg"), math.inf
    if mass is None:
        raise ParameterError(f"--mass: required (or --effective-mass), allowed [{low:g}, "
                             f"{high:g}] kg")
    m1 = check_range("--mass", mass, low=low, high=high, unit="kg")
    if other_mass is None or other_mass == math.inf:
        return m1, math.inf
    return m1, check_range("--other-mass", other_mass, low=low, high=high, unit="kg")


def _law_from_stiffness(mu, stiffness, damping) -> tuple:
    if stiffness is None or damping is None:
        raise ParameterError("--restitution and --touch-duration, or --contact-stiffness and "
                             "--contact-damping: required")
    check_range("--contact-stiffness", stiffness, low=STIFFNESS_RANGE[0],
                high=STIFFNESS_RANGE[1], unit="N/m")
    check_range("--contact-damping", damping, low=DAMPING_RANGE[0], high=DAMPING_RANGE[1],
                unit="N s/m")
    k, c = float(stiffness), float(damping)
    zeta = c / (2.0 * math.sqrt(k * mu))
    omega = math.sqrt(k / mu)
    return restitution_for_damping_ratio(zeta), release_time(zeta) / omega, k, c, zeta


def target_law(mu: float, *, restitution=None, touch_duration=None, contact_stiffness=None,
               contact_damping=None) -> dict:
    """The continuous spring-dashpot F = max(0, k_c delta + c_c delta') on the reduced mass
    mu (kg), from (e, touch duration) or (k_c, c_c): its ``restitution``, ``touch_duration``
    (s, first touch to release), ``contact_stiffness`` k_c (N/m), ``contact_damping`` c_c
    (N s/m), ``damping_ratio`` zeta and ``contact_duration``, the undamped pi sqrt(mu / k_c)
    (s). Raises ParameterError naming the flag that is missing or out of range."""
    if restitution is not None or touch_duration is not None:
        if contact_stiffness is not None or contact_damping is not None:
            raise ParameterError("--contact-stiffness/--contact-damping: give them instead of "
                                 "--restitution and --touch-duration, not with them")
        if restitution is None or touch_duration is None:
            raise ParameterError("--restitution and --touch-duration: give both (or "
                                 "--contact-stiffness and --contact-damping)")
        # e = 1: no damping, which Bullet's implicit contact cannot give (it always damps)
        check_range("--restitution", restitution, low=0.0, high=1.0, low_open=True,
                    high_open=True)
        check_range("--touch-duration", touch_duration, low=TOUCH_DURATION_RANGE[0],
                    high=TOUCH_DURATION_RANGE[1], unit="s")
        zeta = damping_ratio_for_restitution(restitution)
        omega = release_time(zeta) / touch_duration
        k = mu * omega * omega
        c = 2.0 * zeta * math.sqrt(k * mu)
    else:
        restitution, touch_duration, k, c, zeta = _law_from_stiffness(
            mu, contact_stiffness, contact_damping)
    return {"restitution": float(restitution), "touch_duration": float(touch_duration),
            "contact_stiffness": k, "contact_damping": c, "damping_ratio": zeta,
            "contact_duration": math.pi * math.sqrt(mu / k)}


def check_dt(dt, law: dict) -> float:
    """``dt`` (s) within what any engine can be asked: at most
    :data:`MAX_STEPS_PER_COLLISION` steps in the target collision (``law``'s
    touch_duration), at most its duration."""
    if dt is None:
        raise ParameterError("--dt: required, the engines' time step in s")
    low = law["touch_duration"] / MAX_STEPS_PER_COLLISION
    return check_range("--dt", dt, low=low, high=law["touch_duration"], unit="s")


#: The largest relative miss of e or of the touch duration a setting's collision may have
#: for the command to call the target held (issue 41: 10 %).
HOLD_TOLERANCE = 0.10
#: The search for what would hold the target: durations (or steps) a factor SEARCH_RATIO
#: apart, at most SEARCH_STEPS of them (1.05^60 = 18.7 x the target's duration).
SEARCH_RATIO = 1.05
SEARCH_STEPS = 60


def miss(achieved: dict, law: dict) -> float:
    """The larger relative miss of ``achieved``'s restitution and touch_duration (a
    FreeCollision's JSON) against ``law``'s (of :func:`target_law`); inf where not finite."""
    out = max(abs(achieved["restitution"] / law["restitution"] - 1.0),
              abs(achieved["touch_duration"] / law["touch_duration"] - 1.0))
    return out if math.isfinite(out) else math.inf


def _holds(engine, law, mu, m1, m2, dt) -> bool:
    c = ENGINE_REGISTRY[engine].contact_side().collision_at(law, mu, m1, m2, dt)
    return c is not None and miss(c.to_json(), law) <= HOLD_TOLERANCE


def what_holds(engine: str, law: dict, mu: float, m1: float, m2: float, dt: float) -> dict:
    """For a target ``law`` that ``engine`` misses at ``dt`` (s) by more than
    :data:`HOLD_TOLERANCE`: ``smallest_touch_duration``, the shortest touch duration (s, same
    e) this dt holds within it, and ``largest_dt``, the largest step (s) that holds the
    target within it; each the first on a grid :data:`SEARCH_RATIO` apart whose next point
    holds too (the miss oscillates with the steps per touch), None when none of
    :data:`SEARCH_STEPS` does. The bodies of ``m1`` and ``m2`` kg (``mu`` their reduced
    mass)."""
    found = {"smallest_touch_duration": None, "largest_dt": None}
    grid = [SEARCH_RATIO ** k for k in range(1, SEARCH_STEPS + 2)]
    ok = [None] * len(grid)
    for i, f in enumerate(grid):
        t = law["touch_duration"] * f
        if t > TOUCH_DURATION_RANGE[1]:
            break
        ok[i] = _holds(engine, target_law(mu, restitution=law["restitution"],
                                          touch_duration=t), mu, m1, m2, dt)
        if i and ok[i - 1] and ok[i]:
            found["smallest_touch_duration"] = law["touch_duration"] * grid[i - 1]
            break
    low = law["touch_duration"] / MAX_STEPS_PER_COLLISION
    ok = [None] * len(grid)
    for i, f in enumerate(grid):
        if dt / f < low:
            break
        ok[i] = _holds(engine, law, mu, m1, m2, dt / f)
        if i and ok[i - 1] and ok[i]:
            found["largest_dt"] = dt / grid[i - 1]
            break
    return found


def _check_held(out: dict, law: dict, mu, m1, m2, dt, engines) -> None:
    """Mark each engine's result in ``out`` with ``holds_target`` (its setting's collision
    within :data:`HOLD_TOLERANCE` of ``law``) and, where it does not, ``what_holds``."""
    for engine in engines:
        res = out[engine]
        if "error" in res:
            continue
        achieved = ENGINE_REGISTRY[engine].contact_side().achieved(res)
        res["holds_target"] = bool(miss(achieved, law) <= HOLD_TOLERANCE)
        if not res["holds_target"]:
            res["what_holds"] = what_holds(engine, law, mu, m1, m2, dt)


def contact_settings(*, mass=None, other_mass=None, effective_mass=None, restitution=None,
                     touch_duration=None, contact_stiffness=None, contact_damping=None,
                     dt=None, engines=ENGINES) -> dict:
    """Everything ``treeimpact contact`` prints (its JSON): ``inputs``, ``target``
    (:func:`target_law`) and, for each of ``engines`` (:data:`ENGINES`), its settings
    and simulated collisions or ``{"error", "largest_dt"}`` when it cannot hold ``dt``, with
    ``holds_target`` (within :data:`HOLD_TOLERANCE`) and, where not, ``what_holds``
    (each engine's part from its registration's ContactSide, compare.runs.backends.Engine).
    The masses: ``mass`` and ``other_mass`` (None: fixed) or ``effective_mass`` alone
    (:func:`masses`); the collision: ``restitution`` with ``touch_duration``, or
    ``contact_stiffness`` with ``contact_damping`` (:func:`target_law`). Arguments are SI
    (kg, s, N/m, N s/m). Raises ParameterError for bad input."""
    m1, m2 = masses(mass, other_mass, effective_mass)
    mu = m1 if math.isinf(m2) else m1 * m2 / (m1 + m2)
    law = target_law(mu, restitution=restitution, touch_duration=touch_duration,
                     contact_stiffness=contact_stiffness, contact_damping=contact_damping)
    dt = check_dt(dt, law)
    out = {"inputs": {"mass": m1, "other_mass": m2, "effective_mass": mu, "dt": dt,
                      "approach_speed": SPEED},
           "target": law}
    with quiet_stdout():  # PyBullet prints on import; --json keeps stdout for JSON
        for engine in engines:
            out[engine] = ENGINE_REGISTRY[engine].contact_side().settings(law, mu, m1, m2, dt)
        _check_held(out, law, mu, m1, m2, dt, engines)
    return out


