"""The discretised trunks struck through the pad, solved exactly: the engines' hinged chain
(:mod:`.chain`) and MuJoCo's rod (the chain's hinge springs on lumped vertex masses,
mujoco_models/_flex.py) as linear trunks of :class:`analytic.contact.linear_model.LinearImpactModel`,
with the beam rung's pad and exact modal solver (:mod:`.beam_impact`).

What an engine computes, up to its integrator: the reference the segment rule reads the
discretisation error from (:func:`discretisation_errors`). Design notes:
docs/trunk-models.md ("Segments per tree").
"""

from __future__ import annotations

import functools
import math

import numpy as np

from treeimpact.analytic.contact.exact_solve import solve
from treeimpact.analytic.contact.law import collision_duration, contact_law, detection_duration
from treeimpact.analytic.contact.linear_model import LinearImpactModel
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.two_body import two_body_model
from treeimpact.analytic.records import model_metrics, peak_times

from .beam_impact import SAMPLES_PER_COLLISION, beam_impact_model
from .chain import MAX_SEGMENTS, chain_matrices, default_segments, hinged_chain

#: The discretised trunks :func:`discretised_model` builds.
TRUNKS = ("chain", "rod")


def lateral_transform(chain) -> np.ndarray:
    """T with x = T theta: the lateral displacements (m) of ``chain``'s boundaries z_1..z_N
    from its hinge angles (rad), T[i, j] = z_{i+1} - z_j for j <= i, (N, N), invertible
    (diagonal h_j > 0)."""
    z = np.asarray(chain.boundaries)
    return np.maximum(z[1:, None] - z[None, :-1], 0.0)


def lateral_matrices(chain, trunk: str = "chain") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M, D, K) of ``chain`` in its boundaries' lateral displacements x_1..x_N (kg, N s/m,
    N/m). ``trunk`` "chain": the chain's own (:func:`.chain.chain_matrices`, segments'
    masses and rotary inertias); "rod": the same hinge springs with MuJoCo's flex's lumped
    vertex masses rho A (h_{k-1} + h_k) / 2 (+ m_c at a, + m_f at l) and dampers C (h_{k-1} +
    h_k) / 2 (its root body's rho A h_0^3 / 12 on the root hinge neglected)."""
    M_hinge, K_hinge, D_hinge = chain_matrices(chain)
    Ti = np.linalg.inv(lateral_transform(chain))
    K = Ti.T @ K_hinge @ Ti
    if trunk == "chain":
        M, D = Ti.T @ M_hinge @ Ti, Ti.T @ D_hinge @ Ti
    elif trunk == "rod":
        tr = chain.trunk
        h = chain.lengths
        share = 0.5 * (h + np.concatenate([h[1:], [0.0]]))
        m = tr.density * tr.area * share
        m[chain.clamp_index - 1] += tr.clamp_mass
        m[-1] += tr.crown_mass
        M, D = np.diag(m), np.diag(tr.damping * share)
    else:
        raise ParameterError(f"trunk = {trunk!r}: allowed {', '.join(TRUNKS)}")
    return 0.5 * (M + M.T), 0.5 * (D + D.T), 0.5 * (K + K.T)


def discretised_model(scenario: Scenario, segments: int, trunk: str = "chain"):
    """``(LinearImpactModel, TwoBodyModel)``: ``scenario``'s ``trunk`` ("chain" or "rod") of
    ``segments`` segments with the beam rung's pad (k_c, c_c of
    :func:`.beam_impact.beam_impact_model`: the same contact law on the same SDOF model)."""
    beam, sdof = beam_impact_model(scenario)
    chain = hinged_chain(scenario.trunk, segments)
    M, D, K = lateral_matrices(chain, trunk)
    model = LinearImpactModel(
        M=M, D=D, K=K, clamp=chain.clamp_index - 1, crown=chain.segments - 1,
        impactor_mass=beam.impactor_mass, impactor_stiffness=beam.impactor_stiffness,
        impact_speed=beam.impact_speed, contact_stiffness=beam.contact_stiffness,
        contact_damping=beam.contact_damping)
    return model, sdof


def exact_metrics(scenario: Scenario, model: LinearImpactModel, sdof) -> dict:
    """The metrics (:func:`analytic.records.model_metrics`, the engines' rule) of the exact
    solution of ``model`` (its ``sdof`` the two-body model it refines) over ``scenario``'s
    t_end, sampled as the beam rung samples (t_c / 100), and ``x_peaks``: how many
    near-equal maxima x(t) has (:func:`analytic.records.peak_times`)."""
    t_col = collision_duration(sdof, model.contact_stiffness, model.contact_damping)
    samples, _ = solve(model, scenario.t_end, t_col / SAMPLES_PER_COLLISION)
    t_detect = detection_duration(sdof, scenario.contact, stiffness=model.contact_stiffness)
    out = model_metrics(samples, sdof, scenario.impactor, collision_duration=t_detect)
    return {**out, "x_peaks": len(peak_times(samples.t, samples.x))}


@functools.lru_cache(maxsize=32)
def beam_metrics(scenario: Scenario) -> dict:
    """:func:`exact_metrics` of ``scenario``'s beam rung (the default mesh): the reference."""
    return exact_metrics(scenario, *beam_impact_model(scenario))


@functools.lru_cache(maxsize=256)
def discretised_metrics(scenario: Scenario, segments: int, trunk: str = "chain") -> dict:
    """:func:`exact_metrics` of ``scenario``'s ``trunk`` ("chain", "rod") of ``segments``."""
    return exact_metrics(scenario, *discretised_model(scenario, segments, trunk))


def discretisation_errors(scenario: Scenario, segments: int, metrics, trunk: str = "chain"
                          ) -> dict:
    """Relative errors (1) of the exact ``trunk`` ("chain", "rod") of ``segments`` segments
    against the exact beam of ``scenario``, for each of ``metrics`` (names of
    :func:`exact_metrics`'s keys) both have finite and the beam non-zero; others absent
    (t_xmax too when one x(t) has several near-equal maxima and the other one: which peak
    wins flips with small changes, and the ladder flags that t_xmax 'ambiguous', not judged;
    compare.tree.ladder.Ladder._ambiguous_peak)."""
    ref, got = beam_metrics(scenario), discretised_metrics(scenario, int(segments), trunk)
    out = {}
    mixed = (ref["x_peaks"] > 1) != (got["x_peaks"] > 1)
    for k in metrics:
        if k == "t_xmax" and mixed:
            continue
        r, v = ref.get(k, math.nan), got.get(k, math.nan)
        if all(isinstance(x, (int, float)) and math.isfinite(x) for x in (r, v)) and r != 0:
            out[k] = float(v / r - 1.0)
    return out


#: Share of a metric's tolerance the discretisation may take (:func:`converged_segments`);
#: the rest is the engines' integrator's: a quarter, twice the largest share MuJoCo's runs
#: take from the exact chain and rod on open-center at N = 10 (0.12 of the energies' 1 %, 0.08
#: of x_max's 0.5 %; tests/test_chain.py), peak_force aside (its tolerance is the step's lag).
DISCRETISATION_SHARE = 0.75
#: The search's reach over the stiffness-and-frequency rule's N (second-order errors fall 16
#: times over it); a tree not converged there gets the finest N of the reach.
REACH = 4


def converged_segments(scenario: Scenario, tolerances, share: float = DISCRETISATION_SHARE
                       ) -> int:
    """The engines' segments for ``scenario``: the smallest N >= :func:`.chain.default_segments`
    (static stiffness at a and the first two frequencies within 0.5 % of the beam) whose
    exact discretised trunks are within ``share`` (1) of each compared metric's tolerance of
    the exact beam. ``tolerances``: (trunk, metric, rel) triples ("chain" or "rod", a key of
    :func:`exact_metrics`, relative tolerance; t_xmax left out where the ladder does not
    judge it, :func:`discretisation_errors`). Doubling from that N then bisecting,
    up to :data:`REACH` times it (not met there: that N, the finest the search allows)."""
    if isinstance(share, bool) or not isinstance(share, (int, float)) or not 0 < share <= 1:
        raise ParameterError(f"share = {share!r} is out of range: allowed (0, 1]")
    return _converged(scenario, tuple(sorted(tuple(t) for t in tolerances)), float(share))


@functools.lru_cache(maxsize=32)
def _converged(scenario: Scenario, tolerances: tuple, share: float) -> int:
    def within(n: int) -> bool:
        for trunk in sorted({t for t, _, _ in tolerances}):
            rel = {m: v for t, m, v in tolerances if t == trunk and v > 0}
            e = discretisation_errors(scenario, n, rel, trunk)
            if any(abs(v) > share * rel[m] for m, v in e.items()):
                return False
        return True

    n0 = default_segments(scenario.trunk)
    top = min(REACH * n0, MAX_SEGMENTS)
    fail, n = n0 - 1, n0
    while not within(n):
        if n == top:
            return top
        fail, n = n, min(2 * n, top)
    while n - fail > 1:
        mid = (fail + n) // 2
        fail, n = (fail, mid) if within(mid) else (mid, n)
    return n
