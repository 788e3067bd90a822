"""The typed results of the public API (:mod:`treeimpact`): frozen dataclasses with one
documented field per quantity (SI units), built at the API's boundary from what the
backends, the modes and the record fit return inside the package."""

from __future__ import annotations

import dataclasses
import math
import types
from dataclasses import dataclass

from treeimpact.analytic.identify.conclusion import Conclusion
from treeimpact.analytic.identify.diagnosis import (  # noqa: F401 (public)
    Diagnosis,
    DiagnosisKind,
)
from treeimpact.analytic.identify.intervals import UNITS as FIT_UNITS
from treeimpact.analytic.metrics import METRIC_KEYS
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.results import Trajectory


@dataclass(frozen=True)
class Metrics:
    """What one run measured (docs/cli.md; the paper's equations in docs/glossary.md).
    NaN where a backend does not define a quantity (a Newton impact has no peak force).

    Attributes:
        n_impacts: impacts before the bodies move together (eqs 20-21), a count.
        T0: duration of the impact process, first impact to moving together (Table 1), s.
        x0: trunk displacement when the bodies begin to move together (Table 1), m.
        V: their common velocity then (eq 34), m/s.
        x_max: largest displacement of the impact point (eqs 37-38), m.
        t_xmax: its time after the first impact, s.
        t_sep: time the bodies separate after moving together, s.
        A_x: area under x(t) over the impact process (eq 44), m s.
        A_y: area under y(t) over the impact process (eq 44), m s.
        impact_loss: energy lost in the impacts (eq 56), J.
        impact_loss_inelastic: its e = 0 approximation (eq 57), J.
        energy_transferred: energy transferred to the tree (eq 58 with eq 56's loss), J.
        theta_b: the pendulum's rebound angle (eq 58), rad (NaN for a billet).
        ledger_residual: largest energy-ledger error over the input energy, 1.
        energy_delivered: work of the contact force on the trunk over all contacts, J.
        contact_dissipation: energy lost in the contact over all contacts (eq 56 summed), J.
        rebound_energy: the pendulum's energy after its last separation, J.
        impulse: total impulse of the contact force, N s.
        peak_force: largest contact force averaged over one touch duration, N.
        contact_episodes: separate contacts, a count.
        first_contact_duration: the first contact, first touch to release, s.
        crown_peak: largest displacement of the crown at l, m.
        crown_peak_acceleration: largest crown acceleration averaged over one touch
            duration, m/s^2.
    """

    n_impacts: int
    T0: float
    x0: float
    V: float
    x_max: float
    t_xmax: float
    t_sep: float
    A_x: float
    A_y: float
    impact_loss: float
    impact_loss_inelastic: float
    energy_transferred: float
    theta_b: float
    ledger_residual: float
    energy_delivered: float
    contact_dissipation: float
    rebound_energy: float
    impulse: float
    peak_force: float
    contact_episodes: int
    first_contact_duration: float
    crown_peak: float
    crown_peak_acceleration: float

    def as_dict(self) -> dict:
        """The metrics by name (the JSON's ``metrics``)."""
        return dataclasses.asdict(self)


#: The Model fields every backend reports; the others are None where a backend has none.
_MODEL_COMMON = ("M_T", "C_T", "K_T", "m", "k", "restitution", "u1")


@dataclass(frozen=True)
class Model:
    """The two-body model a run used (eqs 7-13, 48) and the backend's settings as run (SI);
    a setting a backend does not have is None.

    Attributes:
        M_T: the trunk's dynamic mass (eq 7), kg.
        C_T: its damping coefficient (eq 10), N s/m.
        K_T: its equivalent stiffness (eq 8), N/m.
        m: the impactor's mass, kg.
        k: the linearised pendulum's spring m g / l_e (eq 13), N/m.
        restitution: e (eq 21), 1.
        u1: the impact speed (eq 48), m/s.
        contact_stiffness: the pad's k_c, N/m (soft contact, beam, engines).
        contact_damping: the pad's c_c, N s/m.
        contact_reduced_mass: the reduced mass the pad meets, kg.
        pad_damping_ratio: c_c / (2 sqrt(k_c mu)) on that mass, 1.
        touch_duration: one free collision under the pad, first touch to release, s.
        engine_contact_stiffness: the stiffness the engine gets after its time-step
            correction, N/m (docs/contact-law.md).
        engine_contact_damping: the damping the engine gets after it, N s/m.
        dt: the engine's time step, s.
        segments: the engine chain's segments (None: the SDOF trunk).
        elements: the beam's finite elements.
        trunk: the engine's trunk model (sdof, chain, flex).
        pendulum: the engine's pendulum model (linear, full).
        trunk_damping_model: how the trunk's C acts (distributed, joint).
        integrator: the engine's integrator.
        calibration: the pad's calibration (pad, effective).
        beam_theory: the beam's theory (euler-bernoulli, timoshenko).
        effective_mass: the trunk's effective mass at the clamp, kg (beam).
        contact_switches: the beam run's contact switches, a count.
        omega_max: the engine trunk's highest natural frequency, rad/s.
        engine_settings: what else the engine reports (solref, solimp, Bullet's contact
            mode, ERP/CFM), read-only.
    """

    M_T: float
    C_T: float
    K_T: float
    m: float
    k: float
    restitution: float
    u1: float
    contact_stiffness: float | None = None
    contact_damping: float | None = None
    contact_reduced_mass: float | None = None
    pad_damping_ratio: float | None = None
    touch_duration: float | None = None
    engine_contact_stiffness: float | None = None
    engine_contact_damping: float | None = None
    dt: float | None = None
    segments: int | None = None
    elements: int | None = None
    trunk: str | None = None
    pendulum: str | None = None
    trunk_damping_model: str | None = None
    integrator: str | None = None
    calibration: str | None = None
    beam_theory: str | None = None
    effective_mass: float | None = None
    contact_switches: int | None = None
    omega_max: float | None = None
    engine_settings: types.MappingProxyType = dataclasses.field(
        default_factory=lambda: types.MappingProxyType({}))

    @classmethod
    def from_dict(cls, model: dict) -> Model:
        """The Model of a backend's model dict (keys beyond the fields: engine_settings)."""
        names = _MODEL_FIELDS
        rest = {k: v for k, v in model.items() if k not in names}
        return cls(**{k: v for k, v in model.items() if k in names},
                   engine_settings=types.MappingProxyType(rest))


#: Model's fields that a backend's model dict fills (the rest goes to engine_settings).
_MODEL_FIELDS = frozenset(f.name for f in dataclasses.fields(Model)) - {"engine_settings"}


@dataclass(frozen=True)
class Simulation:
    """One run of a scenario on a backend (:func:`treeimpact.simulate`).

    Attributes:
        backend: the backend that ran it (analytic, soft, beam, mujoco, bullet).
        metrics: what it measured (:class:`Metrics`, SI).
        model: the two-body model and the settings it ran with (:class:`Model`).
        scenario: the scenario as run: the given one with the options that override it
            (restitution, t_end, contact_stiffness, contact_duration) applied.
        trajectory: the sampled motion, t = 0 at the first contact (s, m, m/s, N), or None.
        result: the backend's own result (``treeimpact.analytic.results.SimulationResult``,
            its metrics and model as dicts), for what the typed fields do not carry.
    """

    backend: str
    metrics: Metrics
    model: Model
    scenario: Scenario
    trajectory: Trajectory | None
    result: object

    def to_json(self) -> dict:
        """What ``treeimpact simulate --json`` prints for this run (without provenance)."""
        return self.result.to_json()


def simulation_of(result, scenario: Scenario) -> Simulation:
    """The :class:`Simulation` of a backend's result and the scenario it ran."""
    metrics = Metrics(**{k: result.metrics[k] for k in METRIC_KEYS})
    return Simulation(backend=result.backend, metrics=metrics,
                      model=Model.from_dict(result.model), scenario=scenario,
                      trajectory=result.trajectory, result=result)


@dataclass(frozen=True)
class TrunkModes:
    """A trunk's static stiffness and natural frequencies.

    Attributes:
        static_stiffness: force over displacement at the clamp height a, N/m.
        omegas: the first natural frequencies, lowest first, rad/s.
        segments: the engine chain's segments (None for the analytic trunks).
    """

    static_stiffness: float
    omegas: tuple
    segments: int | None = None

    def to_json(self) -> dict:
        """The trunk as ``treeimpact modes --json`` writes it (``segments`` only for a
        chain)."""
        out = {"static_stiffness": self.static_stiffness, "omegas": list(self.omegas)}
        return out if self.segments is None else out | {"segments": self.segments}


@dataclass(frozen=True)
class Modes:
    """A backend's trunk beside the continuous Euler-Bernoulli (or Timoshenko) beam
    (:func:`treeimpact.modes`).

    Attributes:
        model: the backend's own trunk (:class:`TrunkModes`).
        beam: the continuous beam's (:class:`TrunkModes`).
    """

    model: TrunkModes
    beam: TrunkModes

    def to_json(self) -> dict:
        """``{"model": ..., "beam": ...}``, as ``treeimpact modes --json`` writes them."""
        return {"model": self.model.to_json(), "beam": self.beam.to_json()}


def modes_of(res: dict) -> Modes:
    """The :class:`Modes` of a backend's modes dict ``res`` ({"model": ..., "beam": ...}:
    static_stiffness N/m, omegas rad/s, segments)."""
    def one(d):
        return TrunkModes(static_stiffness=float(d["static_stiffness"]),
                          omegas=tuple(float(w) for w in d["omegas"]),
                          segments=d.get("segments"))

    return Modes(model=one(res["model"]), beam=one(res["beam"]))


@dataclass(frozen=True)
class Estimate:
    """One identified quantity with its 95 % interval.

    Attributes:
        value: the fitted value (NaN when the record does not fix it), in ``unit``.
        low: the interval's lower end, in ``unit``.
        high: the interval's upper end, in ``unit``.
        determined: False when the record does not fix the quantity (``value`` NaN,
            [low, high] the range it may take).
        unit: the SI unit ("kg", "N/m", "N s/m", "Pa", "1", ...).
    """

    value: float
    low: float
    high: float
    determined: bool
    unit: str


#: The units of the record fit's quantities (SI): analytic.identify.intervals.UNITS.
ESTIMATE_UNITS = FIT_UNITS


@dataclass(frozen=True)
class Identification:
    """A tree identified from a pendulum-test record by the exact 1-DOF model fitted to the
    whole record (:func:`treeimpact.identify`; docs/identification.md). Values of a record
    the model does not explain (``explained`` False) are its best fit, not the tree's.

    Attributes:
        M_T: the dynamic mass, kg (:class:`Estimate`).
        K_T: the equivalent stiffness, N/m.
        C_T: the damping coefficient, N s/m.
        trunk_damping_ratio: C_T / (2 sqrt(K_T M_T)), 1.
        pair_damping_ratio: b / omega_n of the moving-together pair (the paper's xi), 1.
        restitution: the pad's e, 1.
        E: Young's modulus by eq 47, Pa.
        omega_1: the trunk's natural frequency sqrt(K_T / M_T), rad/s.
        V_1: the trunk's velocity after the first impact, m/s.
        t0: the time of the first contact in the record, s.
        x_offset: the trunk sensor's offset, m.
        x_drift: its linear drift, m/s.
        x_drift2: its quadratic drift, m/s^2.
        y_offset: the pendulum sensor's offset, m (None without a y column).
        explained: whether the 1-DOF model explains the record to its noise.
        conclusion: explained (and how) or not (and why): a ``Conclusion``, its ``str()``
            the one line ``identify`` prints.
        diagnoses: what the fit found (:class:`Diagnosis` each: a ``DiagnosisKind`` and a
            one-line message).
        held: the quantities not fitted, name -> why ("given": e passed as
            ``restitution``; "held at 0": a drift the record cannot tell from the motion);
            their intervals are their values.
        note: why a quantity is not fixed ("" when all are).
        residual_rms: the residual's RMS over the samples fitted, m.
        residual_rms_y: that of the pendulum's record, m (None without one).
        noise: the sensor noise estimated from the record, m.
        noise_source: where that estimate comes from (rest, spectrum, resolution).
        misfit_ratio: residual RMS over the noise, 1 (about 1 when explained).
        flagged_rows: the record's rows left out as outliers (file lines).
        warnings: one line each (units, columns ignored, ...).
        fit: the fit's own result (``analytic.identify.record_fit.FitResult``).
        procedure: the paper's procedure (eqs 39-48) on the same record in each of its
            readings (``paper``, ``printed``, ``consistent``; docs/identification.md):
            reading -> M_T (kg), K_T (N/m), C_T (N s/m), E (Pa), pair_damping_ratio and
            trunk_damping_ratio (1), or ``{"error": why}`` where it cannot run.
        record: the :class:`Record` fitted.
    """

    M_T: Estimate
    K_T: Estimate
    C_T: Estimate
    trunk_damping_ratio: Estimate
    pair_damping_ratio: Estimate
    restitution: Estimate
    E: Estimate
    omega_1: Estimate
    V_1: Estimate
    t0: Estimate
    x_offset: Estimate
    x_drift: Estimate
    x_drift2: Estimate
    y_offset: Estimate | None
    explained: bool
    conclusion: Conclusion
    diagnoses: tuple
    held: dict
    note: str
    residual_rms: float
    residual_rms_y: float | None
    noise: float
    noise_source: str
    misfit_ratio: float
    flagged_rows: tuple
    warnings: tuple
    fit: object
    procedure: dict
    record: object


def identification_of(fit, record, procedure: dict) -> Identification:
    """The :class:`Identification` of the record fit's result on ``record`` and the
    paper's ``procedure`` readings on it."""
    def estimate(key):
        if key not in fit.values:
            return None
        low, high = fit.intervals[key]
        value = fit.values[key]
        return Estimate(value=math.nan if value is None else float(value), low=float(low),
                        high=float(high), determined=bool(fit.determined[key]),
                        unit=ESTIMATE_UNITS[key])

    return Identification(
        **{k: estimate(k) for k in ESTIMATE_UNITS}, explained=bool(fit.explained),
        conclusion=fit.conclusion, diagnoses=tuple(fit.diagnoses), held=dict(fit.held),
        note=fit.note, residual_rms=float(fit.residual_rms),
        residual_rms_y=fit.residual_rms_y, noise=float(fit.noise),
        noise_source=fit.noise_source, misfit_ratio=float(fit.misfit_ratio),
        flagged_rows=tuple(record.row(int(i)) for i in fit.flagged),
        warnings=tuple(fit.warnings), fit=fit, procedure=procedure, record=record)

