"""Static stiffness at a and natural frequencies: SDOF reduction next to the continuous beam."""

from __future__ import annotations

import math

from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.reduction import reduce_trunk

from .beam import beam_natural_frequencies, beam_static_stiffness


def beam_reference(scenario: Scenario, n_modes: int = 3,
                   beam_theory: str = "euler-bernoulli") -> dict:
    """The continuous trunk of ``scenario`` (analytic.continuum.beam) in ``beam_theory``,
    Euler-Bernoulli by default: static stiffness at a (N/m) and the lowest ``n_modes``
    natural frequencies (rad/s)."""
    trunk = scenario.trunk
    return {"static_stiffness": float(beam_static_stiffness(trunk, beam_theory)),
            "omegas": [float(w) for w in beam_natural_frequencies(trunk, n_modes, beam_theory)]}


def modes(scenario: Scenario, *, n_modes: int = 3) -> dict:
    """``model``: the SDOF trunk of eq 11 of ``scenario`` (K_T N/m, omega_1 = sqrt(K_T/M_T)
    rad/s); ``beam``: the reference's static stiffness and lowest ``n_modes`` frequencies
    (:func:`beam_reference`)."""
    tree = reduce_trunk(scenario.trunk)
    return {"model": {"static_stiffness": tree.equivalent_stiffness,
                      "omegas": [math.sqrt(tree.equivalent_stiffness / tree.dynamic_mass)]},
            "beam": beam_reference(scenario, n_modes)}
