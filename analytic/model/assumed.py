"""A trunk from what an orchard gives: its geometry and a crown mass estimate, no pendulum
test (issue 50 item 6).

The researcher gives l, a, d, m_c and m_f (and E, rho when known); what nobody measured is
assumed as the registry declares it (analytic.model.registry ``assumed``): the root spring
as the root's share of the static flexibility at the clamp (the paper's rigid clamp, share
0), the distributed damping C as the tree's own damping ratio C_T / (2 sqrt(K_T M_T))
(eq 14, from the paper's two trees), and E and rho when not given. M_T, K_T and C_T then
follow from eqs 7, 8 and 10 (:func:`analytic.model.reduction.reduce_trunk`). Each
assumption's value, range and reason is written into the scenario's ``[calibration]``
notes (:func:`assumption_notes`). SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from treeimpact.analytic.errors import ParameterError

from .calibration import damping_for_ratio, root_for_share
from .parameters import LIMITS, Trunk
from .registry import ASSUMED, BY_NAME

#: The trunk fields a tree from its geometry may assume (``[calibration] assumed``), in the
#: order they are assumed: E and rho first (the root and damping read E I and rho A).
ASSUMABLE = ("trunk.youngs_modulus", "trunk.density", "trunk.base_stiffness", "trunk.damping")


@dataclass(frozen=True)
class GeometryTrunk:
    """A trunk built from its geometry and the assumptions it took.

    Attributes:
        trunk: the :class:`Trunk` (SI).
        assumed: the fields of :data:`ASSUMABLE` assumed, in that order.
        notes: ``assumed_<field>`` -> one line: the value, its range and why.
    """

    trunk: Trunk
    assumed: tuple
    notes: dict


def _value_text(field: str, value: float) -> str:
    p = BY_NAME[field]
    return f"{p.symbol} = {value:.6g} {p.unit}" if math.isfinite(value) else \
        f"{p.symbol} = inf {p.unit} (a rigid clamp)"


def _note(field: str, value: float, span: tuple | None) -> str:
    """One line of an assumption: the field's value, the dimensionless value assumed and
    its range (with the field's values at its ends, ``span``, where they differ), why."""
    a = ASSUMED[field]
    via = BY_NAME[a.via]
    unit = "" if via.unit == "1" else f" {via.unit}"
    head = _value_text(field, value)
    if a.via != field:
        head += f": {via.symbol} = {a.value:g}{unit} assumed"
    else:
        head += " assumed"
    ends = ""
    if span is not None:
        lo, hi = (f"{v:.6g} {BY_NAME[field].unit}" for v in span)
        ends = f", {BY_NAME[field].symbol} from {lo} to {hi} for this trunk"
    return f"{head}, range {a.low:g}-{a.high:g}{unit}{ends}: {a.why}"


def with_root_share(trunk: Trunk, share: float, *, modulus_assumed: bool) -> Trunk:
    """``trunk`` with the root's share ``share`` (1) of its static flexibility at the clamp.
    An assumed E (``modulus_assumed``) is eq 47's rigid-clamp modulus of the paper's two
    trees, the stiffness of wood and root together: the share then splits that flexibility,
    the wood's E becoming E / (1 - share) and k_theta taking the rest (the clamp's static
    stiffness 3 E I / a^3 kept, eq 8). A given E is the wood's own: k_theta is added to it
    (K_T falls with the share). k_theta: analytic.model.calibration.root_for_share."""
    if modulus_assumed and share > 0.0:
        trunk = replace(trunk, youngs_modulus=trunk.youngs_modulus / (1.0 - share))
    return replace(trunk, base_stiffness=root_for_share(trunk, share))


def geometry_trunk(*, length: float, clamp_height: float, diameter: float,
                   clamp_mass: float, crown_mass: float, density: float | None = None,
                   youngs_modulus: float | None = None) -> GeometryTrunk:
    """The trunk of a tree given by its geometry (``length`` l, ``clamp_height`` a,
    ``diameter`` d, in m), its ``clamp_mass`` m_c and ``crown_mass`` m_f (kg) and, when
    known, its wood's ``density`` rho (kg/m^3) and ``youngs_modulus`` E (Pa; None: both
    assumed); the rest assumed as the registry declares (module docstring).

    Returns:
        :class:`GeometryTrunk`.

    Raises:
        ParameterError: a given value out of its range (naming the trunk field), or an
            assumed damping beyond trunk.damping's range (naming the assumption).
    """
    assumed = []
    if youngs_modulus is None:
        youngs_modulus = ASSUMED["youngs_modulus"].value
        assumed.append("trunk.youngs_modulus")
    if density is None:
        density = ASSUMED["density"].value
        assumed.append("trunk.density")
    trunk = Trunk(length=length, clamp_height=clamp_height, diameter=diameter, density=density,
                  youngs_modulus=youngs_modulus, clamp_mass=clamp_mass, crown_mass=crown_mass)
    root, ratio = ASSUMED["base_stiffness"], ASSUMED["damping"]
    e_assumed = "trunk.youngs_modulus" in assumed
    trunk = with_root_share(trunk, root.value, modulus_assumed=e_assumed)
    damping = damping_for_ratio(trunk, ratio.value)
    high = LIMITS["trunk.damping"][1]
    if damping > high:
        raise ParameterError(
            f"trunk.crown_mass = {crown_mass:g} kg: the assumed damping ratio {ratio.value:g} "
            "(eq 14) "
            f"needs a trunk damping C = {damping:.6g} N s/m^2 on this trunk, above the "
            f"{high:g} N s/m^2 allowed (a tree beyond the paper's: measure its damping)")
    trunk = replace(trunk, damping=damping)
    assumed += ["trunk.base_stiffness", "trunk.damping"]
    spans = {"trunk.base_stiffness": tuple(
                 with_root_share(trunk, s, modulus_assumed=e_assumed).base_stiffness
                 for s in (root.low, root.high)),
             "trunk.damping": tuple(damping_for_ratio(trunk, r) for r in
                                    (ratio.low, ratio.high))}
    notes = {f"assumed_{f.split('.')[1]}": _note(f.split(".")[1], getattr(trunk, f.split(".")[1]),
                                                 spans.get(f))
             for f in assumed}
    return GeometryTrunk(trunk=trunk, assumed=tuple(assumed), notes=notes)
