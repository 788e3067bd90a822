"""The continuum trunk struck through the pad: the 1-DOF assumption's reference.

The trunk of :mod:`analytic.continuum.beam` (Hermite cubics or Timoshenko elements, clamp
and crown point masses, root spring, consistent damping of the distributed C of eq 9) and the
linearised pendulum (eq 13) meet through the pad of :mod:`analytic.contact.law`, solved
exactly between contact switches by :mod:`analytic.contact.exact_solve` (the pad's
phases: :mod:`analytic.contact.phases`). Design notes:
docs/beam-impact.md.
"""

from __future__ import annotations

import enum
import functools
from dataclasses import replace

import numpy as np

from treeimpact.analytic.budget import StepCost, check_work
from treeimpact.analytic.contact.exact_record import record as full_record
from treeimpact.analytic.contact.exact_solve import deferred_record, solve
from treeimpact.analytic.contact.law import (
    CALIBRATION,
    CALIBRATIONS,
    collision_duration,
    contact_law,
    detection_duration,
    effective_damping,
    pad_fields,
)
from treeimpact.analytic.contact.linear_model import LinearImpactModel
from treeimpact.analytic.contact.soft import duration_knob
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.options import (
    CONTACT_DURATION,
    CONTACT_STIFFNESS,
    RESTITUTION,
    T_END,
    Option,
)
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.two_body import two_body_model
from treeimpact.analytic.records import model_metrics
from treeimpact.analytic.results import SimulationResult, Trajectory

from .beam import beam_matrices, deflection_dof
from .modes import beam_reference
from .timoshenko import BEAM_THEORIES, check_beam_theory

#: Elements of the default mesh: x_max within 0.05 % of the 48-element mesh
#: (tests/test_beam_impact.py::test_x_max_converges_in_elements).
DEFAULT_ELEMENTS = 12
#: Elements shorter than the trunk's diameter resolve wavelengths shorter than beam theory
#: holds for (docs/beam-impact.md).
MAX_ELEMENTS = 48
#: Samples per free collision of the pad (the soft SDOF rung's record spacing).
SAMPLES_PER_COLLISION = 100
class BeamMethod(enum.StrEnum):
    """How :func:`simulate_beam` evaluates the exact solution (the same solution)."""

    #: the observables on the sample grid, the energies where the metrics read them and the
    #: record when first read (:mod:`analytic.contact.exact_solve`)
    EXACT = "exact"
    #: every sample's state and energies as it goes (the original implementation: the
    #: reference of benchmarks/bench_beam.py and of the tests;
    #: :mod:`analytic.contact.exact_record`)
    EXACT_FULL = "exact-full"


#: The words ``method`` takes (:class:`BeamMethod`).
METHODS = tuple(m.value for m in BeamMethod)
#: The options of :func:`simulate_beam` (the ``beam`` backend).
OPTIONS = {"elements": Option(int, "elements of the beam trunk's mesh", low=2,
                              high=MAX_ELEMENTS),
           "calibration": CALIBRATION, "restitution": RESTITUTION,
           "contact_stiffness": CONTACT_STIFFNESS, "contact_duration": CONTACT_DURATION,
           "t_end": T_END,
           "beam_theory": Option(BEAM_THEORIES, "the trunk's beam theory: euler-bernoulli "
                                                "(the paper's) or timoshenko (shear and rotary "
                                                "inertia, the scenario's trunk.shear_modulus "
                                                "and shear_coefficient)"),
           "method": Option(METHODS, "how the exact solution is evaluated (the same "
                                     "solution)", cli=False)}
#: One sample of the exact solution: wall time and the bytes of the samples and the metrics'
#: work arrays, measured (benchmarks/bench_cost.py; docs/budgets.md).
SAMPLE_COST = StepCost(1e-6, 200.0, "samples of the beam's modal solution")


def beam_impact_model(scenario: Scenario, *, elements: int = DEFAULT_ELEMENTS,
                      calibration: str = "pad", beam_theory: str = "euler-bernoulli"):
    """``(LinearImpactModel, TwoBodyModel)``: the beam problem of ``scenario`` on
    ``elements`` elements and the SDOF model it refines (the scenario's e).

    k_c comes from :func:`analytic.contact.law.contact_law` on the SDOF model (the
    scenario's pad: contact.stiffness, N/m, or contact.duration, s); c_c per
    ``calibration`` (:data:`CALIBRATIONS`); the trunk's ``beam_theory`` of
    :data:`analytic.continuum.timoshenko.BEAM_THEORIES`.
    """
    if isinstance(elements, bool) or not isinstance(elements, (int, np.integer)) or not (
            2 <= elements <= MAX_ELEMENTS):
        raise ParameterError(f"--elements = {elements!r}: allowed integers [2, {MAX_ELEMENTS}]")
    if calibration not in CALIBRATIONS:
        raise ParameterError(f"--calibration = {calibration!r}: allowed "
                             f"{', '.join(CALIBRATIONS)}")
    check_beam_theory(beam_theory)
    sdof = two_body_model(scenario)
    k_c, c_c = contact_law(sdof, scenario.contact)
    M, D, K, nodes, keep = _mesh_matrices(scenario.trunk, int(elements), beam_theory)
    trunk = scenario.trunk
    model = LinearImpactModel(
        M=M, D=D, K=K, clamp=deflection_dof(nodes, keep, trunk.clamp_height),
        crown=deflection_dof(nodes, keep, trunk.length), impactor_mass=sdof.impactor_mass,
        impactor_stiffness=sdof.impactor_stiffness, impact_speed=sdof.impact_speed,
        contact_stiffness=k_c, contact_damping=c_c)
    if calibration == "effective":
        model = replace(model, contact_damping=_effective(model, sdof)(k_c))
    return model, sdof


def _effective(model: LinearImpactModel, sdof):
    """k_c (N/m) -> c_c (N s/m) of the effective convention: e holds for one collision on
    the clamp's effective mass (the pair's reduced mass with it), not on M_T."""
    mu = 1.0 / (1.0 / model.effective_mass + 1.0 / sdof.impactor_mass)
    return lambda k_c: effective_damping(k_c, sdof.restitution, mu)


@functools.lru_cache(maxsize=16)
def _mesh_matrices(trunk, elements: int, beam_theory: str) -> tuple:
    """:func:`beam_matrices` of a (frozen, hashable) trunk, kept for the next model of the
    same mesh (a run builds one, ~0.2 ms; a sweep over the pad meets it again), its arrays
    read-only: the same numbers."""
    out = beam_matrices(trunk, elements, beam_theory)
    for a in out:
        a.setflags(write=False)
    return out


def simulate_beam(scenario: Scenario, *, elements: int = DEFAULT_ELEMENTS,
                  calibration: str = "pad", method: str = "exact",
                  beam_theory: str = "euler-bernoulli"):
    """The scenario with the continuum trunk and the pad, solved exactly to its t_end (s).

    ``elements`` and ``calibration`` as in :func:`beam_impact_model` (the pad: the
    scenario's contact). Returns a SimulationResult (backend "beam") with the metrics of
    :func:`analytic.records.metrics_from_record` (the engines' rule) and the trajectory.
    ``method`` (:class:`BeamMethod`) changes the cost, not the solution; ``beam_theory``
    (``euler-bernoulli`` or ``timoshenko``: shear deformation and rotary inertia, the
    scenario's trunk.shear_modulus and shear_coefficient) the trunk.
    """
    t_end = scenario.t_end
    method = BeamMethod(OPTIONS["method"].check("method", method))
    model, sdof = beam_impact_model(scenario, elements=elements, calibration=calibration,
                                    beam_theory=beam_theory)
    t_col = collision_duration(sdof, model.contact_stiffness, model.contact_damping)

    dt = t_col / SAMPLES_PER_COLLISION
    check_work(t_end, dt, SAMPLE_COST, duration_knob(
        sdof, scenario.contact, SAMPLES_PER_COLLISION,
        _effective(model, sdof) if calibration == "effective" else None))
    t_detect = detection_duration(sdof, scenario.contact, stiffness=model.contact_stiffness)
    if method is BeamMethod.EXACT_FULL:
        record, crown, switches = full_record(model, t_end, dt)
        samples, trajectory = record, record.trajectory()
    else:
        samples, switches = solve(model, t_end, dt)
        record = deferred_record(model, t_end, dt)
        crown = samples.crown
        trajectory = Trajectory(t=samples.t, x=samples.x, vx=samples.vx, y=samples.y,
                                vy=samples.vy, force=samples.force)
    metrics = model_metrics(samples, sdof, scenario.impactor, collision_duration=t_detect)
    model_dict = {**sdof.as_dict(), "elements": int(elements), "beam_theory": beam_theory,
                  "calibration": calibration,
                  "contact_stiffness": model.contact_stiffness,
                  "contact_damping": model.contact_damping,
                  "effective_mass": model.effective_mass, "contact_switches": switches,
                  **pad_fields(model.contact_stiffness, model.contact_damping,
                               1.0 / (1.0 / model.effective_mass + 1.0 / sdof.impactor_mass))}
    return SimulationResult(
        backend="beam", metrics=metrics, model=model_dict, scenario=scenario.to_dict(),
        trajectory=trajectory, record=record, collision_duration=t_col,
        extra={"crown": crown})


def modes(scenario: Scenario, *, elements: int = DEFAULT_ELEMENTS, n_modes: int = 3,
          beam_theory: str = "euler-bernoulli") -> dict:
    """``model``: the backend's mesh of ``elements`` elements for ``scenario`` (static
    stiffness at a, N/m; the lowest ``n_modes`` frequencies, rad/s); ``beam``: the
    160-element reference of :func:`analytic.continuum.modes.beam_reference`, both in
    ``beam_theory``."""
    # lazy: +269 ms at import otherwise (scipy.linalg)
    import scipy.linalg

    model, _ = beam_impact_model(scenario, elements=elements, beam_theory=beam_theory)
    e = np.zeros(model.dofs)
    e[model.clamp] = 1.0
    stiffness = 1.0 / float(np.linalg.solve(model.K, e)[model.clamp])
    w2 = scipy.linalg.eigh(model.K, model.M, eigvals_only=True, subset_by_index=[0, n_modes - 1])
    return {"model": {"static_stiffness": stiffness, "omegas": [float(v) for v in np.sqrt(w2)]},
            "beam": beam_reference(scenario, n_modes, beam_theory)}
