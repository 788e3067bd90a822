"""Findings by physics: which documented departure (a ``[[finding]]`` of
compare/runs/tolerances.toml) a comparison shows, recognised from the tree's physical quantities,
never from its name, so a user's tree gets the verdicts a shipped tree with the same numbers
gets.

Design notes: docs/findings.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario


#: The e at which :meth:`TreePhysics.of` builds the beam model for its effective mass (which
#: the pad does not change): one every pad law takes.
PAD_E = 0.5


@dataclass(frozen=True)
class TreePhysics:
    """The quantities a finding's ``when`` conditions read (each a ``<field>_above`` or
    ``<field>_below`` key in the tolerance file)."""

    restitution: float  # e of the pad (1)
    loss_ratio: float  # mu(M_T) / mu(clamp): eq 56's loss over one collision's on the clamp (1)
    crown_factor: float  # phi(l): the static shape's crown motion per unit x at a (1)

    @classmethod
    def of(cls, scenario: Scenario) -> TreePhysics:
        """The quantities of ``scenario`` (a few ms: the reduction of eqs 7-8 and the
        continuum's mass matrix at the clamp)."""
        # lazy: +130 ms at import otherwise (numpy), which this module's other callers do not need
        from treeimpact.analytic.continuum.beam_impact import beam_impact_model
        from treeimpact.analytic.model.options import scenario_as_run

        # lazy: +54 ms at import otherwise (numpy), which this module's other callers do not need
        from treeimpact.analytic.model.reduction import crown_factor, reduce_trunk

        m = scenario.impactor.mass
        dynamic_mass = reduce_trunk(scenario.trunk).dynamic_mass
        # the beam's effective mass at the clamp: its mesh's, whatever the pad; built at an e
        # the soft pad law takes (e = 0, valid for the Newton model, needs infinite damping)
        m_c = beam_impact_model(scenario_as_run(scenario, {"restitution": PAD_E})
                                )[0].effective_mass
        return cls(restitution=float(scenario.contact.restitution),
                   loss_ratio=_reduced(m, dynamic_mass) / _reduced(m, m_c),
                   crown_factor=float(crown_factor(scenario.trunk)))


def _reduced(a: float, b: float) -> float:
    return a * b / (a + b)


QUANTITIES = tuple(f.name for f in fields(TreePhysics))


def cause_text(finding: dict, physics: TreePhysics) -> str:
    """A finding's ``cause`` in words with this tree's own quantities: its placeholders
    ({restitution}, {loss_ratio}, {crown_factor} of ``physics``, and {one_clamp_collision} =
    1 / loss_ratio - 1, one collision on the clamp against eq 56's loss on M_T) filled."""
    values = {q: getattr(physics, q) for q in QUANTITIES}
    values["one_clamp_collision"] = 1.0 / physics.loss_ratio - 1.0
    return finding["cause"].format(**values)


def validate_cause(where: str, finding: dict) -> None:
    """``finding["cause"]`` fills from a tree's quantities alone (:func:`cause_text`):
    ParameterError naming ``where`` and the placeholder otherwise."""
    try:
        cause_text(finding, TreePhysics(restitution=0.1, loss_ratio=10.0, crown_factor=2.0))
    except (KeyError, ValueError, IndexError) as exc:
        raise ParameterError(f"{where}.cause: {exc!r} is not a tree's quantity (allowed: "
                             f"{', '.join(QUANTITIES)}, one_clamp_collision)") from None


#: What a refusal's ``when`` reads: the Newton record's x0 / x_max.
REFUSAL_QUANTITIES = ("x0_share",)


def validate_when(where: str, when: dict, quantities: tuple = QUANTITIES) -> None:
    """Refuses a ``when`` table naming anything but ``<quantity>_above`` or
    ``<quantity>_below`` of ``quantities`` (a finding's: :class:`TreePhysics`; a refusal's:
    :data:`REFUSAL_QUANTITIES`) with a number; ``where`` names the entry in the message."""
    for key, bound in when.items():
        name, _, side = key.rpartition("_")
        if side not in ("above", "below") or name not in quantities \
                or not isinstance(bound, (int, float)):
            raise ParameterError(f"{where}.when.{key}: a <quantity>_above or _below with a "
                                 f"number; quantities: {', '.join(quantities)}")


def holds(when: dict, values: dict) -> bool:
    """Every condition of ``when`` holds for ``values`` (quantity -> number); a quantity
    that is not finite or not given fails its condition."""
    for key, bound in when.items():
        name, _, side = key.rpartition("_")
        v = values.get(name, math.nan)
        if not math.isfinite(v) or not (v > bound if side == "above" else v < bound):
            return False
    return True


def finding_for(tol: dict, physics: TreePhysics | None, kind: str, metric: str,
                rung_id: str) -> dict | None:
    """The tolerance file ``tol``'s ``[[finding]]`` whose cause ``physics`` shows for
    ``metric`` on a comparison of ``kind`` at ``rung_id``; None without physics or without
    a matching rule."""
    if physics is None:
        return None
    values = {q: getattr(physics, q) for q in QUANTITIES}
    for f in tol.get("finding", []):
        if f["metric"] != metric or kind not in f["kinds"]:
            continue
        if "rungs" in f and rung_id not in f["rungs"]:
            continue
        if holds(f.get("when", {}), values):
            return f
    return None


def finding_band(finding: dict, pair) -> tuple[tuple | None, str]:
    """The band ``finding`` holds on ``pair``'s tree (a :class:`compare.runs.bounds.Pair`) and how
    it follows there: its ``band_bound`` evaluated on the tree's own runs
    (:data:`compare.runs.bounds.continuum.BANDS`) with its words, or its fixed ``band`` with none;
    (None, "") for a ``band_bound`` without a pair to evaluate it on."""
    if "band_bound" not in finding:
        return tuple(finding["band"]), ""
    if pair is None:
        return None, ""
    # lazy: compare.runs.bounds imports the bounds modules, which this module's other callers
    # (the scenario command, the first screen) do not need
    from .bounds.continuum import BANDS

    b = BANDS[finding["band_bound"]](pair, finding)
    if not (math.isfinite(b.lo) and math.isfinite(b.hi)):  # e.g. no value on the other mesh
        return None, f"no band on this tree ({b.words})"
    if not b.lo < b.hi:
        raise ValueError(f"band {finding['band_bound']!r} gave [{b.lo!r}, {b.hi!r}] on "
                         f"{pair.metric}")
    return (float(b.lo), float(b.hi)), b.words


def documented_refusal(tol: dict, reason: str, x0_share: float) -> dict | None:
    """The tolerance file ``tol``'s ``[identification_refused]`` entry whose words (``match``) begin ``reason`` (the
    procedure's refusal) and whose ``when`` holds for the Newton record's ``x0_share`` (x0 / x_max);
    None: the refusal is not documented."""
    for entry in tol.get("identification_refused", {}).values():
        if reason.startswith(entry["match"]) and holds(entry.get("when", {}),
                                                        {"x0_share": x0_share}):
            return entry
    return None
