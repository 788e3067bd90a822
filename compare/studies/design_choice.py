"""A design map's recommendation in the designer's units (issue 50 item 5): the cell a map
recommends (compare.studies.design_words.nearest_within: a/l, m/M_T, contact duration, e)
applied to the tree as its cells are (compare.studies.sweep.apply), then the three choices a
designer makes on a machine, in their units: the clamp height a = (a/l) l (m), the impactor's
mass m = (m/M_T) M_T with eq 7's M_T of the trunk clamped there (kg), the pad as its contact
duration (s) and its stiffness k_c = mu (pi / tau_c)^2 for the 1-DOF pair's reduced mass mu
of these masses (N/m, analytic.contact.law.stiffness_for_duration), and the energy delivered
to the tree at that cell (J) by the continuum trunk (the map's reference) and the 1-DOF
model. Design notes: docs/design-map.md.
"""

from __future__ import annotations

from treeimpact.analytic.contact.law import stiffness_for_duration
from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.two_body import two_body_model

from .design import E_FLOOR, INPUTS
from .small_e import at_restitution


def cell_point(here: dict, pair, at) -> dict:
    """The cell {input: value} a map over ``pair`` recommends at ``at`` (its two values),
    the other inputs at the tree's operating point ``here``, as the map's grid holds them
    (6 significant digits, compare.studies.design.pair_grid)."""
    point = {n: float(f"{here[n]:.6g}") for n in INPUTS if n not in pair}
    point.update({pair[0]: float(at[0]), pair[1]: float(at[1])})
    return {n: point[n] for n in INPUTS}


def designer_choice(scenario, point: dict) -> dict:
    """The cell ``point`` ({input: value}, :data:`~.design.INPUTS`) applied to the tree
    ``scenario``, in the designer's units: ``clamp_height`` (m), ``impactor_mass`` (kg),
    ``contact_duration`` (s), ``contact_stiffness`` k_c = mu (pi / tau_c)^2 (N/m, mu the
    1-DOF pair's reduced mass of the impactor and eq 7's M_T there), ``energy_delivered``
    (J, the continuum trunk's at e, read at E_FLOOR below it) and
    ``energy_delivered_one_dof`` (J, the exact 1-DOF model's), with ``point``."""
    # lazy: +62 ms at import otherwise (treeimpact.compare.studies.sweep.apply), which the study's
    # other readers (the words, the answer) do not need
    from .sweep.apply import apply_point

    s, _ = apply_point(scenario, dict(point))
    mu = two_body_model(s).reduced_mass
    duration = float(point["contact_duration"])
    run = at_restitution(s, max(s.contact.restitution, E_FLOOR))
    return {"point": dict(point), "clamp_height": float(s.trunk.clamp_height),
            "impactor_mass": float(s.impactor.mass), "contact_duration": duration,
            "contact_stiffness": float(stiffness_for_duration(mu, duration)),
            "energy_delivered": float(simulate_beam(run).metrics["energy_delivered"]),
            "energy_delivered_one_dof": float(
                simulate(run, samples=2).metrics["energy_delivered"])}


def choice_text(choice: dict, lead: str = "For this tree") -> str:
    """:func:`designer_choice`'s ``choice`` in words after ``lead``: 'For this tree: clamp
    at 0.341 m, a 26.4 kg impactor and a 7.45 ms pad (k_c = 4.1e+05 N/m for these masses);
    the tree takes 12.3 J there (the 1-DOF model 11.1 J).'"""
    return (f"{lead}: clamp at {choice['clamp_height']:.3g} m, a "
            f"{choice['impactor_mass']:.3g} kg impactor and a "
            f"{1e3 * choice['contact_duration']:.3g} ms pad (k_c = "
            f"{choice['contact_stiffness']:.3g} N/m for these masses); the tree takes "
            f"{choice['energy_delivered']:.3g} J there (the 1-DOF model "
            f"{choice['energy_delivered_one_dof']:.3g} J).")
