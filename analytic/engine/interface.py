"""What every physics-engine backend shares (MuJoCo, PyBullet): the interface they implement,
their common options, and the run protocol around the engine's own stepping (validation,
divergence checks, record to metrics and result, modes from M, K, J). SI units throughout;
design notes in docs/engines.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Protocol, runtime_checkable

import numpy as np

from treeimpact.analytic.contact.law import CALIBRATION, CALIBRATIONS
from treeimpact.analytic.continuum.chain import (
    MAX_SEGMENTS,
    SEGMENTS,
    default_segments,
    hinged_chain,
)
from treeimpact.analytic.continuum.modes import beam_reference
from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.model.options import CONTACT_STIFFNESS, RESTITUTION, T_END, Option
from treeimpact.analytic.model.parameters import Pendulum, Scenario
from treeimpact.analytic.model.two_body import TwoBodyModel, two_body_model
from treeimpact.analytic.records import model_metrics, with_static_shape_crown
from treeimpact.analytic.results import SimulationResult

#: Options every engine takes: trunk model, pendulum model, chain damping model.
TRUNKS = ("sdof", "chain")
PENDULUMS = ("linear", "full")
DAMPINGS = ("distributed", "joint")
#: Largest time step an engine run is asked for (s): the pad's collision lasts 0.5 ms by
#: default and needs several steps (the engines refuse an unstable step with its limit).
MAX_DT = 1e-3
#: The options every engine's ``simulate`` takes (each engine adds its own:
#: ``mujoco_models.options``, ``bullet_models.options``).
ENGINE_OPTIONS = {
    "trunk": Option(TRUNKS, "trunk model: the paper's SDOF (slide joint) or the hinged chain"),
    "segments": SEGMENTS,
    "pendulum": Option(PENDULUMS, "pendulum model: linearised (eq 13) or released from "
                                  "theta_r"),
    "trunk_damping_model": Option(DAMPINGS, "how the trunk's damping C (trunk.damping, N s/m^2) "
                                  "acts: distributed along the trunk (the paper's, eq 9) or "
                                  "lumped in the chain's joints"),
    "contact_stiffness": CONTACT_STIFFNESS,
    "dt": Option(float, "time step (default: from the contact and the chain's highest mode)",
                 "s", 0.0, MAX_DT, low_open=True),
    "restitution": RESTITUTION,
    "t_end": T_END,
    "calibration": CALIBRATION,
}
#: Mechanical energy above (1 + this) x the input, or created by the engine beyond this
#: fraction of it, is a diverged run (every rung's own ledger tolerance is below 2 %).
ENERGY_GROWTH_LIMIT = 0.05


@dataclass(frozen=True)
class EngineSetup:
    """What every engine's setup holds: the scenario and its two-body model, the trunk,
    pendulum and damping models, the chain's segments (None: SDOF), dt and t_end (s)."""

    scenario: Scenario
    model: TwoBodyModel
    trunk: str
    pendulum: str
    damping: str
    segments: int | None
    dt: float
    t_end: float


@runtime_checkable
class Engine(Protocol):
    """A physics-engine backend: a module with these four names (mujoco_models,
    bullet_models); ``compare.runs.backends`` registers it by name."""

    OPTIONS: dict  # option name -> treeimpact.analytic.model.options.Option

    def make_setup(self, scenario: Scenario, **options) -> EngineSetup:
        """Validate the ``options`` and build the engine's model of ``scenario``: everything
        a run needs."""

    def run(self, setup: EngineSetup):
        """Step one setup; a SimulationResult, or SimulationDiverged raised."""

    def simulate(self, scenario: Scenario, **options):
        """``run(make_setup(scenario, **options))``."""

    def modes(self, scenario: Scenario, *, segments=None, n_modes: int = 3) -> dict:
        """Static stiffness at a (N/m) and the lowest ``n_modes`` natural frequencies
        (rad/s) of the engine's chain for ``scenario`` (``segments``: None, the default
        count) (:func:`chain_modes`) beside the continuous beam's."""


def check_choice(name: str, value, allowed):
    """``value`` if it is one of ``allowed``, else a one-line error naming ``--name``."""
    if value not in allowed:
        raise ParameterError(f"--{name} = {value!r}: allowed {', '.join(allowed)}")
    return value


#: The chain-only options an SDOF trunk has no use for, and why (refused when given with
#: ``--trunk sdof``, as ``--segments`` is by :func:`trunk_chain`).
SDOF_IGNORES = {
    "trunk_damping_model": "the SDOF trunk's damping is C_T at the clamp (eq 11), lumped "
                           "in one slide joint",
    "calibration": "the SDOF trunk's effective mass at the clamp is M_T, so 'pad' and "
                   "'effective' set the same pad",
}


def trunk_options(trunk: str, trunk_damping_model, calibration) -> tuple[str, str]:
    """The ``trunk_damping_model`` and ``calibration`` of a run of ``trunk`` (their defaults
    where None); a one-line error naming the flag when one is given for ``trunk = sdof``,
    which it does not change (:data:`SDOF_IGNORES`)."""
    if trunk == "sdof":
        given = {"trunk_damping_model": trunk_damping_model, "calibration": calibration}
        for name, value in given.items():
            if value is not None:
                flag = "--" + name.replace("_", "-")
                raise ParameterError(f"{flag} = {value!r}: only for a --trunk with segments, "
                                     f"not --trunk sdof ({SDOF_IGNORES[name]})")
    damping = DAMPINGS[0] if trunk_damping_model is None else trunk_damping_model
    return damping, CALIBRATIONS[0] if calibration is None else calibration


def engine_model(scenario: Scenario, *, trunk: str, pendulum: str, trunk_damping_model: str,
                 calibration: str, trunks: tuple = TRUNKS) -> TwoBodyModel:
    """The options every engine shares, checked (one-line errors), and the scenario's
    two-body model (eqs 7-13, 48). An engine run ends at the scenario's t_end (s): a run
    option that overrides it or e is applied to the scenario before
    (analytic.model.options.scenario_as_run).

    ``trunk``, ``pendulum``, ``trunk_damping_model`` and ``calibration`` are checked against
    their choices; ``pendulum = "full"`` needs a pendulum impactor; ``trunks``: the engine's
    trunk models (default the shared ones).
    """
    check_choice("trunk", trunk, trunks)
    check_choice("pendulum", pendulum, PENDULUMS)
    check_choice("trunk_damping_model", trunk_damping_model, DAMPINGS)
    check_choice("calibration", calibration, CALIBRATIONS)
    if not isinstance(scenario, Scenario):
        raise ParameterError("scenario: expected an analytic.Scenario")
    if pendulum == "full" and not isinstance(scenario.impactor, Pendulum):
        raise ParameterError("--pendulum = 'full': the scenario's impactor is a billet")
    return two_body_model(scenario)


def trunk_chain(scenario: Scenario, trunk: str, segments, *, engine: str = "the engine",
                max_segments: int = MAX_SEGMENTS):
    """The hinged chain of ``scenario``'s trunk for a ``chain`` trunk (default segment count
    when ``segments`` is None), None for ``sdof`` (which takes no --segments); a one-line
    error naming ``engine`` when the chain needs more segments than it takes
    (``max_segments``)."""
    if trunk == "chain":
        n = default_segments(scenario.trunk) if segments is None else segments
        if isinstance(n, int) and n > max_segments:
            if segments is not None:
                raise ParameterError(f"--segments = {n}: {engine} takes at most "
                                     f"{max_segments}")
            raise ParameterError(
                f"--trunk chain: this trunk needs {n} segments to be within 0.5 % of the beam, "
                f"and {engine} takes at most {max_segments}: --segments {max_segments} (a "
                "coarser chain), or another backend")
        return hinged_chain(scenario.trunk, n)
    if segments is not None:
        raise ParameterError("--segments: only for --trunk chain")
    return None


def swing_time(pendulum: Pendulum) -> float:
    """Exact time (s) of the full pendulum's swing from rest at theta_r to the bottom:
    K(sin(theta_r / 2)) sqrt(l_e / g)."""
    # lazy: +251 ms at import otherwise (scipy.special)
    from scipy.special import ellipk

    s = math.sin(pendulum.release_angle_rad / 2.0)
    return float(ellipk(s * s) * math.sqrt(pendulum.equivalent_length / pendulum.gravity))


def check_energy(backend: str, mechanical: np.ndarray, initial_energy: float, dt: float
                 ) -> None:
    """SimulationDiverged, its message naming ``backend`` and the step ``dt`` (s), when the
    bodies' ``mechanical`` energy (J) leaves the finite or exceeds (1 +
    ENERGY_GROWTH_LIMIT) x the input ``initial_energy`` (J)."""
    mech = np.asarray(mechanical)
    if not np.all(np.isfinite(mech)) or np.max(mech) > (1.0 + ENERGY_GROWTH_LIMIT) * (
            initial_energy):
        raise SimulationDiverged(
            f"{backend}: mechanical energy reached {np.nanmax(mech):.4g} J > "
            f"{1 + ENERGY_GROWTH_LIMIT:g} x the input {initial_energy:.4g} J (dt = {dt:.3g} s)")


def engine_result(backend: str, record, *, scenario: Scenario, model: TwoBodyModel,
                  t_end: float, collision_duration: float, detection_duration: float,
                  initial_energy: float, model_fields: dict, extra: dict | None = None):
    """The SimulationResult of ``backend`` from its ImpactRecord ``record`` (t = 0 at the
    touch): the crown from the static shape of eq 5 unless the record has the chain's own,
    the metrics of :func:`analytic.records.model_metrics` on ``detection_duration`` (s) and
    the ``initial_energy`` (J), the model dict (two-body ``model`` + ``model_fields``), the
    ``scenario`` as run (its e and ``t_end``, s); ``collision_duration`` (s) the result's
    free-collision time and ``extra`` added to its diagnostics."""
    if record.crown is None:
        record = with_static_shape_crown(record, scenario.trunk)
    metrics = model_metrics(record, model, scenario.impactor,
                            collision_duration=detection_duration,
                            initial_energy=initial_energy)
    scen = scenario.to_dict()
    scen["contact"]["restitution"] = model.restitution
    scen["t_end"] = t_end
    return SimulationResult(
        backend=backend, metrics=metrics, model={**model.as_dict(), **model_fields},
        scenario=scen, trajectory=record.trajectory(), record=record, collision_duration=collision_duration,
        extra={"initial_energy": initial_energy, **(extra or {})})


def with_crown(record, crown: np.ndarray, crown_velocity: np.ndarray):
    """``record`` with the chain top's motion: ``crown`` (m) and ``crown_velocity`` (m/s)."""
    return replace(record, crown=crown, crown_velocity=crown_velocity)


def chain_modes(scenario: Scenario, mass_matrix: np.ndarray, hinge_stiffness: np.ndarray,
                impact_jacobian: np.ndarray, n_modes) -> dict:
    """An engine chain's modes from its ``mass_matrix`` M (kg m^2), ``hinge_stiffness`` k_j
    (N m/rad) and the impact point's ``impact_jacobian`` J = dx(a)/dtheta (m/rad): static
    stiffness K_a = 1 / (J K^-1 J^T) (N/m), the lowest ``n_modes`` omega^2 = eig(K, M)
    (rad/s); ``beam``: the continuous beam of ``scenario``
    (:func:`analytic.continuum.modes.beam_reference`)."""
    # lazy: +193 ms at import otherwise (scipy.linalg)
    import scipy.linalg

    kd = np.asarray(hinge_stiffness, dtype=float)
    n = kd.size
    if isinstance(n_modes, bool) or not isinstance(n_modes, int) or not 1 <= n_modes <= n:
        raise ParameterError(f"n_modes = {n_modes!r} is out of range: allowed [1, {n}]")
    static = float(1.0 / np.sum(np.asarray(impact_jacobian) ** 2 / kd))
    w2 = scipy.linalg.eigh(np.diag(kd), mass_matrix, eigvals_only=True,
                           subset_by_index=[0, n_modes - 1])
    return {"model": {"static_stiffness": static, "omegas": [float(v) for v in np.sqrt(w2)],
                      "segments": n},
            "beam": beam_reference(scenario, n_modes)}


def step_means(p: np.ndarray, on: np.ndarray) -> np.ndarray:
    """Mean of a sampled power ``p`` (W) over each step n (samples n, n+1), n = 0 .. N-2,
    for an integrator whose stage forces are not recorded (RK4's damping work).

    Inside a run of samples with the same contact state ``on`` (the power is smooth there)
    the cubic through four samples of the run is integrated: (-1, 13, 13, -1) / 24 centred,
    (9, 19, -5, 1) / 24 or (1, -5, 19, 9) / 24 at the ends of the run (error O(h^4)); the
    trapezoid where the run is shorter and on a step where the contact state changes.
    """
    N = len(p)
    out = 0.5 * (p[:-1] + p[1:])
    if N < 2:
        return out
    n = np.arange(N - 1)
    run = np.concatenate([[0], np.cumsum(on[1:] != on[:-1])])
    same = run[:-1] == run[1:]

    def inrun(i):
        return (i >= 0) & (i < N) & (run[np.clip(i, 0, N - 1)] == run[n])

    def at(i):
        return p[np.clip(i, 0, N - 1)]

    central = same & inrun(n - 1) & inrun(n + 2)
    forward = same & ~central & inrun(n + 2) & inrun(n + 3)
    backward = same & ~central & ~forward & inrun(n - 2) & inrun(n - 1)
    out = np.where(central, (-at(n - 1) + 13.0 * at(n) + 13.0 * at(n + 1) - at(n + 2)) / 24.0,
                   out)
    out = np.where(forward, (9.0 * at(n) + 19.0 * at(n + 1) - 5.0 * at(n + 2) + at(n + 3))
                   / 24.0, out)
    return np.where(backward, (at(n - 2) - 5.0 * at(n - 1) + 19.0 * at(n) + 9.0 * at(n + 1))
                    / 24.0, out)
