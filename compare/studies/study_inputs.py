"""The inputs of the sensitivity study (compare.studies.sensitivity, .sobol): which are
unmeasured (names, units, ranges and reasons the registry's), which a tree's file says were
measured (held) or assumed, each input's value on a tree (:func:`inputs_of`), its range on
that tree (:func:`ranges_of`, compare.studies.input_ranges) and the tree at a design point
(:func:`vary`: a measured tree keeps its M_T, K_T and C_T, a tree from its geometry its
geometry, E and crown). SI units; docs/sensitivity.md.
"""

from __future__ import annotations

import math
from dataclasses import replace

from treeimpact.analytic.model.assumed import with_root_share
from treeimpact.analytic.model.calibration import (
    MeasuredTree,
    calibrate_trunk,
    damping_for_ratio,
)
from treeimpact.analytic.model.parameters import Contact
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.registry import BY_NAME
from treeimpact.analytic.model.scenario import assumed_fields, measured_fields
from treeimpact.analytic.model.two_body import two_body_model

from .input_ranges import tree_ranges

#: The unmeasured inputs, in the order of the Morris design's columns (its seed reads them in
#: this order): each varied over the registry's ``unmeasured`` range.
ORDER = ("clamp_mass", "e_over_g", "log10_pad_duration", "restitution", "root_share", "density")


def _input(name: str) -> tuple:
    """(low, high, unit, why the range, the measurement that would fix it) of the input
    ``name``, as the registry declares it (analytic.model.registry ``unmeasured``)."""
    p = BY_NAME[name]
    u = p.unmeasured
    return (u.low, u.high, p.unit, u.why, u.measure)


#: The unmeasured inputs: (low, high, unit, why the range, the measurement that would fix it);
#: names, units, ranges and reasons are the registry's.
INPUTS = {name: _input(name) for name in ORDER}
#: The inputs only a tree from its geometry has (its damping, and E when not given, assumed,
#: not measured), after :data:`ORDER` in its design's columns.
GEOMETRY_ORDER = ("damping_ratio", "youngs_modulus")
#: Every input a study may vary: :data:`INPUTS`, then a geometry tree's own.
ALL_INPUTS = INPUTS | {name: _input(name) for name in GEOMETRY_ORDER}

#: The scenario field that fixes each input when the file says it was measured
#: (``[calibration] measured``, analytic.model.scenario.MEASURABLE).
FIELDS = {"clamp_mass": (BY_NAME["clamp_mass"].path,), "e_over_g": ("trunk.shear_modulus",),
          "log10_pad_duration": ("contact.duration", "contact.stiffness"),
          "restitution": (BY_NAME["restitution"].path,), "root_share": ("trunk.base_stiffness",),
          "density": (BY_NAME["density"].path,), "damping_ratio": (BY_NAME["damping"].path,),
          "youngs_modulus": (BY_NAME["youngs_modulus"].path,)}


def from_geometry(scenario) -> bool:
    """Whether ``scenario`` is a tree built from its geometry: its file lists assumed fields
    (``[calibration] assumed``), so its M_T, K_T and C_T were not measured."""
    return bool(assumed_fields(scenario))


def measured_inputs(scenario) -> tuple[str, ...]:
    """The inputs of :data:`INPUTS` the scenario's file says were measured (held at the
    file's values by the study)."""
    fields = set(measured_fields(scenario))
    return tuple(n for n, f in FIELDS.items() if fields & set(f))


def free_inputs(scenario=None) -> tuple[str, ...]:
    """The inputs the study varies: :data:`INPUTS` (with a tree from its geometry, and
    :data:`GEOMETRY_ORDER`'s it assumed: its damping, its E when not given) less the
    scenario's measured ones."""
    held = measured_inputs(scenario) if scenario is not None else ()
    names = tuple(INPUTS)
    if scenario is not None and from_geometry(scenario):
        assumed = set(assumed_fields(scenario))
        names += tuple(n for n in GEOMETRY_ORDER if set(FIELDS[n]) & assumed)
    return tuple(n for n in names if n not in held)


def inputs_of(scenario) -> dict:
    """The scenario's own value of every input of :data:`INPUTS` (its units): E/G from the
    shear modulus (0 without one), the pad's 1-DOF collision time from its stiffness when
    the file gives that, the root's share of the static flexibility at the clamp from the
    trunk's E I and the reduced K_T (eq 8); a tree from its geometry also its damping ratio
    C_T / (2 sqrt(K_T M_T)) (eq 14)."""
    t, c = scenario.trunk, scenario.contact
    g = t.shear_modulus
    duration = c.duration
    if duration is None and c.stiffness is not None:
        mu = two_body_model(scenario).reduced_mass
        duration = math.pi / math.sqrt(c.stiffness / mu)  # s, the undamped 1-DOF collision
    bending = t.clamp_height ** 3 / (3.0 * t.bending_stiffness)  # m/N
    tree = reduce_trunk(t)
    out = {"clamp_mass": t.clamp_mass, "density": t.density, "restitution": c.restitution,
           "e_over_g": t.youngs_modulus / g if g is not None and math.isfinite(g) else 0.0,
           "log10_pad_duration": math.log10(duration) if duration else math.nan,
           "root_share": 0.0 if math.isinf(t.base_stiffness)  # a rigid clamp: exactly 0
           else 1.0 - bending * tree.equivalent_stiffness}
    if from_geometry(scenario):
        out |= {"damping_ratio": tree.damping_ratio, "youngs_modulus": t.youngs_modulus}
    return out


def problem(names=None, ranges: dict | None = None) -> dict:
    """The SALib problem: names and bounds of :data:`INPUTS` (only ``names`` when given),
    the bounds the tree's (``ranges``, compare.studies.input_ranges.tree_ranges) when
    given, else the registry's."""
    names = list(INPUTS) if names is None else list(names)
    return {"num_vars": len(names), "names": names,
            "bounds": [[ranges[n]["low"], ranges[n]["high"]] if ranges
                       else list(ALL_INPUTS[n][:2]) for n in names]}


def ranges_of(scenario, names=None) -> dict:
    """The ranges of the free inputs ``names`` (default :func:`free_inputs`) on the tree
    ``scenario``: compare.studies.input_ranges.tree_ranges, the rules that keep each point
    a valid tree with the measured M_T and K_T. A tree from its geometry measured neither
    (:func:`vary` keeps its geometry, E and crown; the root share sets k_theta alone): those
    rules do not apply and each range is the registry's, which keeps every point a tree."""
    names = free_inputs(scenario) if names is None else tuple(names)
    if from_geometry(scenario):
        return {n: {"low": float(ALL_INPUTS[n][0]), "high": float(ALL_INPUTS[n][1]),
                    "registry": [ALL_INPUTS[n][0], ALL_INPUTS[n][1]], "clipped": ""}
                for n in names}
    return tree_ranges(scenario, names, inputs_of(scenario))


def vary(scenario, p: dict):
    """``scenario`` at the unmeasured inputs ``p`` (:data:`ALL_INPUTS`), keeping what was
    measured and only that. A measured tree (Table 1's kind): M_T, K_T and C_T kept (the
    crown, root spring and damping recalibrated, eqs 7, 8, 10), E from the root's share of
    K_T's flexibility. A tree from its geometry (:func:`from_geometry`): its geometry, its
    E when given and its crown kept (an assumed E as ``p`` says), the root spring set from
    the root's share with that E I and the damping from the damping ratio (eq 14), so M_T,
    K_T and C_T move (eqs 7, 8, 10). Both: the clamp
    mass, the density, G = E / (E/G), the pad's duration and e as ``p`` says. Returns
    (scenario, the beam backend's beam theory)."""
    if from_geometry(scenario):
        return _vary_geometry(scenario, p)
    trunk = scenario.trunk
    tree = reduce_trunk(trunk)
    m = scenario.impactor.mass
    measured = MeasuredTree(dynamic_mass=tree.dynamic_mass,
                            equivalent_stiffness=tree.equivalent_stiffness,
                            damping_rate=tree.equivalent_damping / (2.0 * (tree.dynamic_mass + m)))
    a = trunk.clamp_height
    e_mod = a ** 3 * tree.equivalent_stiffness / (
        3.0 * trunk.second_moment * (1.0 - p["root_share"]))
    ratio = p["e_over_g"]
    chosen = replace(trunk, clamp_mass=p["clamp_mass"], density=p["density"],
                     youngs_modulus=e_mod, shear_modulus=e_mod / ratio if ratio > 0 else None)
    contact = Contact(restitution=p["restitution"],
                      duration=10.0 ** p["log10_pad_duration"])
    varied = replace(scenario, trunk=calibrate_trunk(chosen, measured, impactor_mass=m),
                     contact=contact)
    return varied, "timoshenko" if ratio > 0 else "euler-bernoulli"


def _vary_geometry(scenario, p: dict):
    """:func:`vary` of a tree from its geometry: l, a, d and m_f kept; m_c, rho, E (its own
    when ``p`` has none) and G set, then the root's share (analytic.model.assumed
    .with_root_share: an assumed E, wood and root together, split by it at the clamp's
    static stiffness; a given E, the wood's, with k_theta added) and C from the damping
    ratio (damping_for_ratio, eqs 7, 8, 10, 14) of that trunk."""
    trunk, ratio = scenario.trunk, p["e_over_g"]
    chosen = replace(trunk, clamp_mass=p["clamp_mass"], density=p["density"],
                     youngs_modulus=p.get("youngs_modulus", trunk.youngs_modulus))
    chosen = with_root_share(chosen, p["root_share"], modulus_assumed="trunk.youngs_modulus"
                             in assumed_fields(scenario))
    e_wood = chosen.youngs_modulus
    chosen = replace(chosen, shear_modulus=e_wood / ratio if ratio > 0 else None)
    chosen = replace(chosen, damping=damping_for_ratio(chosen, p["damping_ratio"]))
    contact = Contact(restitution=p["restitution"], duration=10.0 ** p["log10_pad_duration"])
    return (replace(scenario, trunk=chosen, contact=contact),
            "timoshenko" if ratio > 0 else "euler-bernoulli")


def inputs_entry(names, ranges: dict | None) -> dict:
    """study.json's ``inputs``: per input of ``names`` its range on the tree (low, high,
    from ``ranges``, compare.studies.input_ranges; None: the registry's), unit, why,
    the measurement that settles it, the registry's range and why the tree's differs
    (``clipped``, '' when not; compare.studies.input_ranges)."""
    out = {}
    for n in names:
        v = ALL_INPUTS[n]
        r = (ranges or {}).get(n) or {"low": v[0], "high": v[1], "clipped": ""}
        out[n] = {"low": r["low"], "high": r["high"], "unit": v[2], "why": v[3],
                  "settle": v[4], "registry": [v[0], v[1]], "clipped": r["clipped"]}
    return out
