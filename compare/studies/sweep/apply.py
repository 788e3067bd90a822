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

import math

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.ratios import apply_ratio
from treeimpact.analytic.model.registry import set_field

from .grid import DERIVED_RATIOS, OPTION, SCENARIO, resolve_parameter


def _set(scenario: Scenario, target: str, value) -> Scenario:
    """The registry's :func:`~treeimpact.analytic.model.registry.set_field`."""
    return set_field(scenario, target, value)


def _ratio(scenario: Scenario, name: str, ratio: float) -> Scenario:
    """The registry's ratio ``name`` applied (analytic.model.ratios)."""
    if name not in DERIVED_RATIOS:  # pragma: no cover - resolve_parameter admits only these
        raise ParameterError(f"--grid {name!r}: unknown ratio")
    return apply_ratio(scenario, name, ratio)


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
