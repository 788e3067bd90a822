"""Apply a grid point to a scenario: ``dataclasses.replace`` on the frozen parameters.

Order (so each derived ratio is solved against the final values of what it depends on):

1. direct scenario fields (dotted names and their aliases), in grid order;
2. ``a_over_l``: clamp_height = ratio * length;
3. ``crown_ratio``: crown_mass = ratio * trunk_mass (rho A l, independent of the masses);
4. ``mass_ratio``: impactor mass = ratio * M_T, with M_T (eq 7) of the trunk from steps 1-3
   (M_T does not depend on the impactor).

Engine options of the point are returned separately. The rebuilt dataclasses validate
themselves, so a point outside a parameter's range raises the parameter's one-line
:class:`ParameterError` (prefixed with the grid name when it differs).
"""

from __future__ import annotations

import dataclasses
import math

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario

from .grid import DERIVED_RATIOS, OPTION, SCENARIO, resolve_parameter


def _set(scenario: Scenario, target: str, value) -> Scenario:
    if "." not in target:
        return dataclasses.replace(scenario, **{target: value})
    section, field = target.split(".")
    part = getattr(scenario, section)
    changes = {field: value}
    if section == "impactor" and field == "release_angle_deg":
        if not hasattr(part, "release_angle_deg"):
            raise ParameterError(f"{target}: the scenario's impactor is a "
                                 f"{type(part).__name__.lower()}, which has no release angle")
    elif field not in {f.name for f in dataclasses.fields(part)}:
        raise ParameterError(f"{target}: the scenario's {section} is a "
                             f"{type(part).__name__.lower()}, which has no field {field!r}")
    if section == "contact" and field == "stiffness":
        changes["duration"] = None  # stiffness and duration are exclusive (analytic.Contact)
    elif section == "contact" and field == "duration":
        changes["stiffness"] = None
    return dataclasses.replace(scenario, **{section: dataclasses.replace(part, **changes)})


def _ratio(scenario: Scenario, name: str, ratio: float) -> Scenario:
    from treeimpact.analytic.model.reduction import reduce_trunk

    t = scenario.trunk
    if name == "a_over_l":
        value = ratio * t.length
    elif name == "crown_ratio":
        value = ratio * t.trunk_mass
    elif name == "mass_ratio":
        value = ratio * reduce_trunk(t).dynamic_mass
    else:  # pragma: no cover - resolve_parameter admits only DERIVED_RATIOS
        raise ParameterError(f"--grid {name!r}: unknown ratio")
    return _set(scenario, DERIVED_RATIOS[name][0], value)


def apply_point(scenario: Scenario, point: dict) -> tuple[Scenario, dict]:
    """(scenario with the point's parameters, engine options of the point)."""
    params = {name: resolve_parameter(name) for name in point}
    options = {}
    scen = scenario
    for name, p in params.items():  # record.* axes are the analysis's, not the run's
        if p.kind == OPTION:
            options[p.target] = point[name]
    try:
        for name, p in params.items():
            if p.kind == SCENARIO:
                current = name
                scen = _set(scen, p.target, point[name])
        for ratio in DERIVED_RATIOS:
            if ratio in point:
                current = ratio
                if not isinstance(point[ratio], (int, float)) or not math.isfinite(point[ratio]):
                    raise ParameterError(f"{ratio} = {point[ratio]!r}: expected a finite number")
                scen = _ratio(scen, ratio, float(point[ratio]))
    except ParameterError as exc:
        msg = str(exc)
        raise ParameterError(msg if msg.startswith(current) else f"{current} = "
                             f"{point[current]!r}: {msg}") from None
    return scen, options
