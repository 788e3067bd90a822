"""The sensitivity study's input ranges for one tree (issue 50 item 4): the registry's
``unmeasured`` range of each input (analytic.model.registry), clipped where a value of it
could not describe the tree it is applied to. The study keeps each tree's measured M_T and
K_T (compare.studies.study_inputs.vary), so three physical rules bound the inputs:

1. **E within its allowed range.** The root's share s of the static flexibility at the
   clamp sets E = E_0 / (1 - s), E_0 = a^3 K_T / (3 I) the rigid-root modulus (eq 8); E must
   lie in trunk.youngs_modulus's allowed range, so s <= 1 - E_0 / E_high and
   s >= 1 - E_0 / E_low; the root spring k_theta = a^2 K_T / s must reach
   trunk.base_stiffness's lower limit: s <= a^2 K_T / k_theta_low.
2. **G within its allowed range.** G = E / (E/G) must reach trunk.shear_modulus's lower
   limit at the softest E of the range: E/G <= E_0 / ((1 - s_low) G_low).
3. **A crown of no negative mass.** M_T = rho A J(s) + m_c + m_f phi(l)^2 (eq 7) with
   m_f >= 0: the bare trunk rho A J + m_c may not exceed the measured M_T at any point of
   the box. Its heaviest corner (the densest wood, the heaviest clamp, the largest J over
   the root-share range) is brought down to M_T by shrinking the upper ends of the wood
   density and the clamp mass in proportion to the mass each adds over its range; an
   input held as measured keeps its value. When even the lightest corner exceeds M_T no
   range is valid: the ranges are kept and said to be so, and the study's points fail
   with their reasons.

Each range says whether and why it was clipped (:func:`tree_ranges`); the study page and
study.json state the clipped ranges. SI units (the registry's).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from treeimpact.analytic.model.parameters import LIMITS
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.registry import BY_NAME

#: Root shares at which J (the square integral of the static shape, eq 7) is evaluated for
#: rule 3's heaviest corner: its range's ends and points between them.
J_SAMPLES = 9
#: Rule 3 leaves this share of M_T to the crown at the heaviest corner: the crown mass
#: of that corner is then positive in floating point (the calibration refuses m_f < 0).
MASS_MARGIN = 1e-6


def registry_range(name: str) -> tuple[float, float]:
    """The registry's ``unmeasured`` range of the input ``name`` (its unit)."""
    u = BY_NAME[name].unmeasured
    return u.low, u.high


def _rigid_modulus(trunk) -> float:
    """E_0 = a^3 K_T / (3 I), Pa: the modulus that gives the tree's K_T with a rigid root
    (eq 8)."""
    equivalent_stiffness = reduce_trunk(trunk).equivalent_stiffness
    return trunk.clamp_height ** 3 * equivalent_stiffness / (3.0 * trunk.second_moment)


def _share_range(trunk, low: float, high: float) -> tuple[float, float, str]:
    """Rule 1 on the root share's range [low, high]: (low, high, why clipped or '')."""
    e0 = _rigid_modulus(trunk)
    e_low, e_high = LIMITS["trunk.youngs_modulus"][:2]
    equivalent_stiffness = reduce_trunk(trunk).equivalent_stiffness
    top = min(1.0 - e0 / e_high, trunk.clamp_height ** 2 * equivalent_stiffness
              / LIMITS["trunk.base_stiffness"][0])
    bottom = max(1.0 - e0 / e_low, 0.0)
    lo, hi = max(low, bottom), min(high, top)
    if (lo, hi) == (low, high):
        return low, high, ""
    if not hi > lo:  # no valid range: kept as it is, said so
        return low, high, (f"no valid range: E = E_0 / (1 - s) with E_0 = {e0:.4g} Pa "
                           f"(eq 8) leaves {e_low:g}-{e_high:g} Pa for no s in it")
    return lo, hi, (f"E = E_0 / (1 - s) with E_0 = a^3 K_T / (3 I) = {e0:.4g} Pa (eq 8) "
                    f"must lie in {e_low:g}-{e_high:g} Pa and the root spring a^2 K_T / s "
                    f"reach {LIMITS['trunk.base_stiffness'][0]:g} N m/rad")


def _wood_area_j(trunk, share: float) -> float:
    """A J(s), m^3: the bare trunk's mass per unit density at root share ``share``
    (eq 7's rho A J; J of the static shape with E and the root spring that keep K_T)."""
    equivalent_stiffness = reduce_trunk(trunk).equivalent_stiffness
    e_mod = _rigid_modulus(trunk) / (1.0 - share)
    base = trunk.clamp_height ** 2 * equivalent_stiffness / share if share > 0 else math.inf
    bare = replace(trunk, youngs_modulus=e_mod, base_stiffness=base, crown_mass=0.0,
                   clamp_mass=0.0, damping=0.0)
    return reduce_trunk(bare).dynamic_mass / trunk.density


def _mass_ranges(trunk, ranges: dict, held: dict) -> dict:
    """Rule 3 on the density's and the clamp mass's ranges (``ranges``: name -> [low, high,
    why]; ``held``: the measured inputs' values): the ranges, clipped where needed."""
    dynamic_mass = reduce_trunk(trunk).dynamic_mass
    s_lo, s_hi = ranges["root_share"][:2] if "root_share" in ranges else \
        (held["root_share"],) * 2
    aj = max(_wood_area_j(trunk, s) for s in np.linspace(s_lo, s_hi, J_SAMPLES))
    rho = ranges["density"][:2] if "density" in ranges else (held["density"],) * 2
    m_c = ranges["clamp_mass"][:2] if "clamp_mass" in ranges else (held["clamp_mass"],) * 2
    budget = dynamic_mass * (1.0 - MASS_MARGIN)
    room = budget - rho[0] * aj - m_c[0]  # kg the box's upper ends may add
    span = (rho[1] - rho[0]) * aj + (m_c[1] - m_c[0])  # kg they add
    if span <= room:
        return ranges
    out = dict(ranges)
    if room <= 0:  # no valid box: kept as they are, said so
        why = (f"no valid range: the lightest bare trunk rho A J + m_c = "
               f"{rho[0] * aj + m_c[0]:.4g} kg exceeds M_T = {dynamic_mass:.4g} kg (eq 7)")
        for name in ("density", "clamp_mass"):
            if name in out:
                out[name] = [*out[name][:2], why]
        return out
    f = room / span
    why = (f"the bare trunk rho A J + m_c may not exceed M_T = {dynamic_mass:.4g} kg "
           f"(eq 7, crown m_f >= 0; A J up to {aj:.4g} m^3): upper ends shrunk to {f:.3f} of "
           "their span")
    for name, (lo, hi) in (("density", rho), ("clamp_mass", m_c)):
        if name in out:
            out[name] = [lo, lo + f * (hi - lo), why]
    return out


def tree_ranges(scenario, names, own: dict) -> dict:
    """The ranges of the inputs ``names`` (the study's free ones) on the tree ``scenario``:
    name -> {low, high, registry (the registry's [low, high]), clipped (why, '' when
    not)} by the module's three rules; ``own``: every input's value on the tree
    (compare.studies.study_inputs.inputs_of; the held ones enter the rules at it). Units:
    the registry's."""
    held = {k: v for k, v in own.items() if k not in names}
    trunk = scenario.trunk
    ranges = {n: [*registry_range(n), ""] for n in names}
    if "root_share" in ranges:
        ranges["root_share"] = list(_share_range(trunk, *ranges["root_share"][:2]))
    if "e_over_g" in ranges:
        s_lo = ranges["root_share"][0] if "root_share" in ranges else held["root_share"]
        soft = _rigid_modulus(trunk) / (1.0 - s_lo)
        top = soft / LIMITS["trunk.shear_modulus"][0]
        lo, hi = ranges["e_over_g"][:2]
        if hi > top:
            ranges["e_over_g"] = [lo, top, f"G = E / (E/G) must reach "
                                  f"{LIMITS['trunk.shear_modulus'][0]:g} Pa at the softest "
                                  f"E = {soft:.4g} Pa"]
    if {"density", "clamp_mass"} & set(ranges):
        ranges = _mass_ranges(trunk, ranges, held)
    return {n: {"low": float(v[0]), "high": float(v[1]),
                "registry": list(registry_range(n)), "clipped": v[2]}
            for n, v in ranges.items()}
