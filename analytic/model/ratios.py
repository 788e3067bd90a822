"""The registry's ratios applied to a scenario: a / l, m_f / m_trunk and m / M_T each solve
the field they name (:attr:`~.registry.Parameter.sets`) against the scenario's other values
(eq 7 for M_T). Above :mod:`.registry` and :mod:`.reduction`, which the ratio m / M_T reads.
"""

from __future__ import annotations

from .registry import BY_NAME, set_field
from .reduction import reduce_trunk


def _base(scenario, name: str) -> float:
    """What the ratio ``name`` is a ratio of: l (m), rho A l (kg) or M_T (kg, eq 7)."""
    t = scenario.trunk
    return {"a_over_l": lambda: t.length, "crown_ratio": lambda: t.trunk_mass,
            "mass_ratio": lambda: reduce_trunk(t).dynamic_mass}[name]()


#: The registry's ratios, by name.
RATIOS = tuple(p.name for p in BY_NAME.values() if p.sets is not None)


def apply_ratio(scenario, name: str, ratio: float):
    """``scenario`` with the field the ratio ``name`` sets at ``ratio`` times its base:
    a = (a/l) l, m_f = ratio rho A l, m = ratio M_T (eq 7). KeyError for a non-ratio."""
    return set_field(scenario, BY_NAME[name].sets, ratio * _base(scenario, name))


def ratio_of(scenario, name: str) -> float:
    """The ratio ``name`` of ``scenario``: the field it sets over its base (a / l, m_f /
    (rho A l), m / M_T with eq 7's M_T), the one place each ratio's formula is written.
    KeyError for a non-ratio."""
    section, _, field = BY_NAME[name].sets.partition(".")
    return getattr(getattr(scenario, section), field) / _base(scenario, name)


def apply_input(scenario, name: str, value):
    """``scenario`` with the registry's input ``name`` (a field or a ratio) at ``value``."""
    p = BY_NAME[name]
    return apply_ratio(scenario, name, value) if p.sets is not None else p.apply(scenario, value)
