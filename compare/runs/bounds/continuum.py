"""Bounds on the continuum's physical steps (Timoshenko against Euler-Bernoulli, the pad's
convention) and the bands of the 1-DOF assumption's findings (the beam against the soft
SDOF), each from the tree's own geometry, masses and runs.

A finding's band (``band_bound = "NAME"`` in a ``[[finding]]``) is registered here by
:func:`register_band`; its function returns a :class:`FindingBand`, the range the step must
lie in and how it follows with this tree's numbers. Design notes: docs/findings.md
("Bands").
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

from treeimpact.analytic.model.options import scenario_as_run

from .base import Bound, Pair, register


@dataclass(frozen=True)
class FindingBand:
    """A finding's band on one tree.

    Attributes:
        lo: the lowest relative step the cause allows (1).
        hi: the highest (1), > lo.
        words: how the band follows, with this tree's numbers (one clause).
    """

    lo: float
    hi: float
    words: str


BandFunction = Callable[[Pair, dict], FindingBand]
#: name -> the function that evaluates a finding's band on a :class:`Pair` and the finding.
BANDS: dict[str, BandFunction] = {}


def register_band(name: str) -> Callable[[BandFunction], BandFunction]:
    """Decorator: register the finding band ``name`` (a finding's ``band_bound = "name"``)."""
    def deco(fn: BandFunction) -> BandFunction:
        if name in BANDS:
            raise ValueError(f"band {name!r} registered twice")
        BANDS[name] = fn
        return fn
    return deco


def _mu(a: float, b: float) -> float:
    return a * b / (a + b)


def _masses(pair: Pair) -> tuple[float, float, float, float, float]:
    """(m, M_T, m_c, u, e) of the checked beam run's model: the impactor's mass, eq 7's M_T,
    the clamp's instantaneous effective mass (kg), the impact speed (m/s) and the pad's e."""
    mo = pair.rung.result.model
    return mo["m"], mo["M_T"], mo["effective_mass"], mo["u1"], mo["restitution"]


# --------------------------------------------------------------------------- finding bands


@register_band("clamp_to_M_T_loss")
def clamp_to_m_t_loss(pair: Pair, finding: dict) -> FindingBand:
    """The pad's loss over all contacts lies between one collision on the clamp's
    instantaneous effective mass m_c, (1 - e^2) mu(m, m_c) u^2 / 2 (every later contact only
    adds, and a lighter mass is damped more by the same pad), and the plastic loss on M_T,
    mu(m, M_T) u^2 / 2 (the mass the pendulum meets grows from m_c towards M_T, never beyond);
    relative to the soft SDOF's loss on the same tree (``pair``: the beam run against the
    soft SDOF's); ``finding`` unused (the signature)."""
    m, dynamic_mass, m_c, u, e = _masses(pair)
    ref = pair.reference_value
    one = (1 - e * e) * 0.5 * _mu(m, m_c) * u * u
    plastic = 0.5 * _mu(m, dynamic_mass) * u * u
    lo, hi = one / ref - 1, plastic / ref - 1
    return FindingBand(lo, hi, (
        f"band from one collision on the clamp's {m_c:.2f} kg, (1 - e^2) mu u^2 / 2 = "
        f"{one:.3g} J ({lo:+.1%}), to the plastic loss on M_T = {dynamic_mass:.0f} kg, "
        f"{plastic:.3g} J ({hi:+.1%}), against the SDOF's {ref:.3g} J"))


@register_band("clamp_to_M_T_force")
def clamp_to_m_t_force(pair: Pair, finding: dict) -> FindingBand:
    """The mean contact force over t_c is the first contact's impulse, (1 + e) mu u, over
    t_c, and grows with the mass the pad presses on: from the clamp's instantaneous effective
    mass (mu(m, m_c) / mu(m, M_T) - 1 = 1 / loss_ratio - 1; a lighter mass rebounds less,
    which only lowers it) up to M_T (the SDOF's own, 0). ``pair``: the beam run against the
    soft SDOF's (its TreePhysics); ``finding`` unused."""
    lo = 1.0 / pair.physics.loss_ratio - 1.0
    return FindingBand(lo, 0.0, (
        f"band from the impulse on the clamp's effective mass, 1 / loss_ratio - 1 = {lo:+.1%}"
        f" (loss_ratio = {pair.physics.loss_ratio:.1f}), to the impulse on M_T (+0%)"))


@register_band("mesh")
def mesh(pair: Pair, finding: dict) -> FindingBand:
    """No physical prediction of the size: the band is the step measured with the beam at
    twice its elements (half, where twice exceeds the mesh's limit) within ``finding``'s
    ``mesh_rel`` (1) of that run's value, so the size the check reports is the continuum's,
    not its mesh's. ``pair``: the beam run against its reference."""
    n, other, v = mesh_value(pair)
    ref, tol = pair.reference_value, float(finding["mesh_rel"])
    s = v / ref - 1
    half = tol * abs(1 + s)
    return FindingBand(s - half, s + half, (
        f"no physical prediction of its size: the step at {other} elements is {s:+.1%}, the "
        f"band that step +- {tol:.1%} of the value (mesh convergence, {n} -> {other} elements)"))


def mesh_value(pair: Pair) -> tuple[int, int, float]:
    """(N, N', value): the checked beam run's elements N, the other mesh N' (2 N, or N / 2
    where 2 N exceeds the limit) and the metric's value there (SI) with the same pad, for
    ``pair``'s tree, beam run and metric."""
    # lazy: the exact solver's module (numpy, scipy) only where a mesh band is evaluated
    from treeimpact.analytic.continuum.beam_impact import MAX_ELEMENTS

    mo = pair.rung.result.model
    n = int(mo["elements"])
    other = 2 * n if 2 * n <= MAX_ELEMENTS else max(2, n // 2)
    as_run = scenario_as_run(pair.scenario, {  # the rung's e, pad and t_end
        "restitution": float(mo["restitution"]),
        "contact_stiffness": float(mo["contact_stiffness"]),
        "t_end": float(pair.rung.result.scenario["t_end"])})
    metrics = _beam_metrics(as_run, other, mo["calibration"], mo["beam_theory"])
    value = metrics.get(pair.metric)
    return n, other, (math.nan if value is None else float(value))


@functools.lru_cache(maxsize=8)
def _beam_metrics(scenario, elements: int, calibration: str, beam_theory: str) -> dict:
    """The beam run's metrics of ``scenario`` (as run) on ``elements`` elements (its
    ``calibration``, ``beam_theory``):
    kept for the tree's other metrics (one run, under a second)."""
    # lazy: the exact solver (numpy, scipy) only where a mesh band is evaluated
    from treeimpact.analytic.continuum.beam_impact import simulate_beam

    return dict(simulate_beam(scenario, elements=elements, calibration=calibration,
                              beam_theory=beam_theory).metrics)


# --------------------------------------------------------------------------- Timoshenko


def shear_flexibility(pair: Pair) -> float:
    """delta (1): the flexibility the shear adds at a, 1 / K_Timoshenko - 1 / K_EB over
    1 / K_EB (analytic.continuum.beam.beam_static_stiffness of ``pair``'s trunk, exact)."""
    # lazy: the beam's matrices (numpy) only where a Timoshenko bound is evaluated
    from treeimpact.analytic.continuum.beam import beam_static_stiffness

    trunk = pair.scenario.trunk
    return beam_static_stiffness(trunk) / beam_static_stiffness(trunk, "timoshenko") - 1.0


def impulse_ceiling(scenario, elements: int, beam_theory: str, where: str,
                    power: int = 1) -> float:
    """sum_n |phi_n(a) phi_n(z)| / omega_n^power: at ``power`` 1 (m / (N s)) the ceiling of
    the displacement at z (``where``: "clamp" z = a, "crown" z = l) per unit impulse at a
    of the ``scenario``'s trunk on ``elements`` elements in ``beam_theory`` (mass-normalised
    modes phi_n, all in phase); at 2 (m/N, clamp) the static flexibility at a, the check
    of the modes."""
    # lazy: the beam's matrices and scipy's eigensolver only where the bound is evaluated
    import numpy as np
    import scipy.linalg
    from treeimpact.analytic.continuum.beam_impact import beam_impact_model

    # the mesh's modes, whatever the pad: built at an e the soft pad law takes (e = 0 needs
    # infinite damping)
    model, _ = beam_impact_model(scenario_as_run(scenario, {"restitution": 0.5}),
                                 elements=elements, beam_theory=beam_theory)
    w2, v = scipy.linalg.eigh(np.asarray(model.K), np.asarray(model.M))
    at = model.clamp if where == "clamp" else model.crown
    return float(np.sum(np.abs(v[model.clamp] * v[at]) / w2 ** (power / 2)))


def _shear_response(pair: Pair, where: str) -> Bound:
    """:func:`shear_clamp_response`'s and :func:`shear_crown_response`'s bound on ``pair``
    at ``where`` ("clamp" or "crown")."""
    elements = int(pair.rung.result.model["elements"])
    ceil = [impulse_ceiling(pair.scenario, elements, theory, where)
            for theory in ("euler-bernoulli", "timoshenko")]
    c = ceil[1] / ceil[0] - 1
    j = pair.rung.values.get("impulse", math.nan) / pair.reference.values.get(
        "impulse", math.nan) - 1
    j = abs(j) if math.isfinite(j) else 0.0  # not parted for good by t_end: the modes alone
    delta = shear_flexibility(pair)
    rel = (1 + c) * (1 + j) - 1
    return Bound(rel, (
        f"shear adds delta = {delta:.1%} to the static flexibility at a (the 1-DOF x_max "
        f"sqrt(1 + delta) - 1 = {math.sqrt(1 + delta) - 1:+.1%}), its modes' impulse "
        f"response ceiling at the {where} moves by {c:+.1%}, the impulse by |j| = {j:.1%}: "
        f"(1 + {c:.3f})(1 + {j:.3f}) - 1 = {rel:.1%}"))


@register("shear_clamp_response")
def shear_clamp_response(pair: Pair) -> Bound:
    """x_max: in the 1-DOF picture x_max = J / (M_T omega) = J sqrt(f / M_T) (J the
    impulse, f the static flexibility at a: a peak sqrt(1 + delta) - 1 higher with the
    shear's delta); on the continuum the clamp's response per unit impulse at a is at most
    sum_n phi_n(a)^2 / omega_n (all modes in phase), which the shear raises by lowering each
    omega_n, the higher modes most. The peak moves by at most that ceiling's step times the
    impulse's, (1 + c)(1 + |j|) - 1, both of this tree's trunk and runs (``pair``: the
    Timoshenko run against the Euler-Bernoulli one)."""
    return _shear_response(pair, "clamp")


@register("shear_crown_response")
def shear_crown_response(pair: Pair) -> Bound:
    """crown_peak: as :func:`shear_clamp_response` with the crown's response per unit
    impulse at a, ceiling sum_n |phi_n(a) phi_n(l)| / omega_n (``pair`` as there)."""
    return _shear_response(pair, "crown")


@register("energy_room")
def energy_room_bound(pair: Pair) -> Bound:
    """The energy delivered by the Timoshenko continuum cannot exceed the impactor's energy
    m u^2 / 2 less one collision's loss on its clamp's effective mass,
    (1 - e^2) mu(m, m_c) u^2 / 2 (the pad loses at least that, the impactor keeps >= 0):
    relative to the Euler-Bernoulli delivery, the room the energy balance leaves (``pair``:
    the Timoshenko run against the Euler-Bernoulli one)."""
    m, _, m_c, u, e = _masses(pair)
    most = 0.5 * m * u * u - (1 - e * e) * 0.5 * _mu(m, m_c) * u * u
    ref = pair.reference_value
    if not (math.isfinite(ref) and ref > 0):  # no delivery to compare: the check is skipped
        return Bound(0.0, "no energy delivered on the Euler-Bernoulli run")
    return Bound(most / ref - 1, (
        f"at most m u^2 / 2 - (1 - e^2) mu(m, m_c) u^2 / 2 = {most:.3g} J (m_c = {m_c:.2f} "
        f"kg) against {ref:.3g} J delivered: {most / ref - 1:.1%}"))


# --------------------------------------------------------------------------- convention


def clamp_restitution(pair: Pair) -> float:
    """The pad convention's e on the clamp (1): its c_c, calibrated on M_T, at the damping
    ratio it has against the reduced mass with the clamp's effective mass (the reference
    run's ``pad_damping_ratio`` of ``pair``)."""
    # lazy: the contact law only where a convention bound is evaluated
    from treeimpact.analytic.contact.law import restitution_for_damping_ratio

    return restitution_for_damping_ratio(float(pair.reference.result.model["pad_damping_ratio"]))


@register("convention_impulse")
def convention_impulse_bound(pair: Pair) -> Bound:
    """The mean force over t_c is the first collision's impulse (1 + e) mu u over t_c: the
    effective convention restores e on the clamp where the pad's c_c (calibrated on M_T)
    rebounds at e_c, so the force moves by at most (1 + e) / (1 + e_c) - 1 (``pair``: the
    effective convention's run against the pad's)."""
    e = float(pair.rung.result.model["restitution"])
    e_c = clamp_restitution(pair)
    c_ratio = pair.rung.result.model["contact_damping"] / pair.reference.result.model[
        "contact_damping"]
    rel = (1 + e) / (1 + e_c) - 1
    return Bound(rel, (
        f"c_c x {c_ratio:.2f} on the clamp's effective mass: e = {e:g} there instead of the "
        f"pad's e_c = {e_c:.3f}, (1 + e) / (1 + e_c) - 1 = {rel:.1%}"))
