"""Result types shared by every backend (analytic, soft contact, MuJoCo, PyBullet).

All backends return a :class:`SimulationResult` whose ``metrics`` dict has exactly the keys
of :data:`analytic.metrics.METRIC_KEYS` (SI units: ``METRIC_UNITS``), so ``compare`` never
branches on the backend. Each metric is declared once, in :data:`analytic.metrics.METRICS`.
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
from dataclasses import dataclass, field
from pathlib import PurePath

import numpy as np

from .errors import OutsideValidity, ParameterError, SimulationDiverged
from .metrics import METRICS
from .threads import blas_limit

class Deferred:
    """Mixin of frozen dataclasses that can be sampled on first read of any field:
    ``cls.deferred(sample)`` where ``sample()`` returns the full instance (the exact
    solver's results: sweeps never read them, so they never pay for them). ``sample`` must
    pickle (a module-level function or a partial of one)."""

    @classmethod
    def deferred(cls, sample):
        """An instance whose fields ``sample()`` (returning the full instance) fills on the
        first read of any of them."""
        obj = cls.__new__(cls)
        object.__setattr__(obj, "_sample", sample)
        return obj

    def __getattr__(self, name):  # called only for fields not set yet: a deferred instance
        sample = self.__dict__.get("_sample")
        if sample is None or name not in self.__dataclass_fields__:
            raise AttributeError(name)
        with blas_limit():  # read after the API call returned: the library's limit again
            full = sample()
        for f in self.__dataclass_fields__:
            object.__setattr__(self, f, getattr(full, f))
        del self.__dict__["_sample"]
        return getattr(self, name)


@dataclass(frozen=True)
class Trajectory(Deferred):
    """Sampled motion; t = 0 at the first contact. x: trunk impact point, y: pendulum."""

    t: np.ndarray  # s
    x: np.ndarray  # m
    vx: np.ndarray  # m/s
    y: np.ndarray  # m
    vy: np.ndarray  # m/s
    force: np.ndarray | None = None  # N, contact force on the trunk (>= 0)


@dataclass(frozen=True)
class ImpactRecord(Deferred):
    """A sampled simulation, t = 0 at the first contact (all SI: s, m, m/s, N, J).

    ``x``/``vx``: trunk impact point; ``y``/``vy``: pendulum contact point; ``force``: contact
    force on the trunk (>= 0). Energies: ``kinetic`` and ``potential`` of both bodies
    (springs and gravity), ``damping_work`` dissipated by the trunk's damping so far,
    ``contact_work`` absorbed by the contact so far (integral of F (vy - vx) dt: stored plus
    dissipated), ``contact_potential`` elastic energy held in the contact now,
    ``pendulum_energy`` the pendulum's own kinetic + potential energy. Optional: ``crown``
    (m) and ``crown_velocity`` (m/s), the top mass's motion, where the backend has it.
    """

    t: np.ndarray
    x: np.ndarray
    vx: np.ndarray
    y: np.ndarray
    vy: np.ndarray
    force: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    damping_work: np.ndarray
    contact_work: np.ndarray
    contact_potential: np.ndarray
    pendulum_energy: np.ndarray
    crown: np.ndarray | None = None
    crown_velocity: np.ndarray | None = None

    def __post_init__(self):
        n = np.shape(self.t)
        for name in self.__dataclass_fields__:
            if getattr(self, name) is None:
                continue
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != n:
                raise ParameterError(f"record.{name}: shape {value.shape}, expected {n}")
            object.__setattr__(self, name, value)
        if n[0] < 3 or np.any(np.diff(self.t) <= 0):
            raise ParameterError("--t-end / --dt: the record has fewer than 3 increasing times: a "
                             "longer --t-end or a smaller --dt (record.t)")

    def contact_loss(self, t: float) -> float:
        """The contact's work less the elastic energy it holds at time ``t`` (s), J: what the
        contact has lost so far, interpolated linearly between samples."""
        return float(np.interp(t, self.t, self.contact_work)) - float(
            np.interp(t, self.t, self.contact_potential))

    def ledger_residual(self, initial_energy: float) -> float:
        """max |kinetic + potential + damping work + contact work - initial| / initial over the
        samples (``initial_energy`` J)."""
        total = self.kinetic + self.potential + self.damping_work + self.contact_work
        return float(np.max(np.abs(total - initial_energy)) / initial_energy)

    def trajectory(self):
        """The record's motion and force as the result's :class:`analytic.results.Trajectory`."""
        return Trajectory(t=self.t, x=self.x, vx=self.vx, y=self.y, vy=self.vy,
                          force=self.force)


@dataclass(frozen=True)
class SimulationResult:
    """What every backend returns: metrics (METRIC_KEYS, SI), the model and scenario as
    dicts, the sampled motion, and what the backend solved: ``solution`` (the exact solver's
    :class:`analytic.impact.solution.ImpactSolution`, Newton rungs) or ``record`` (the sampled
    :class:`analytic.results.ImpactRecord` with forces and energies, soft-contact rungs) with
    ``collision_duration`` (s, the free-collision duration its impacts are told apart by).
    ``extra``: backend diagnostics for people (JSON-able); no code reads it."""

    backend: str
    metrics: dict
    model: dict
    scenario: dict
    trajectory: Trajectory | None = None
    extra: dict = field(default_factory=dict)
    solution: object | None = None  # analytic.impact.solution.ImpactSolution
    record: ImpactRecord | None = None
    collision_duration: float = math.nan

    def to_json(self) -> dict:
        """backend, model, metrics and scenario, JSON-safe (NaN and inf as None)."""
        return {"backend": self.backend, "model": to_jsonable(self.model),
                "metrics": to_jsonable(self.metrics), "scenario": to_jsonable(self.scenario)}


@dataclass(frozen=True)
class FreeCollision:
    """One free two-body collision as an engine stepped it (``treeimpact contact``): the
    rebound ratio ``restitution`` (1; NaN if the step blew up), ``touch_duration`` (s, first
    touch to release: the law force reaching zero), ``steps`` with a pushing force, and
    ``peak_penetration`` (m, the largest overlap of the two bodies, at the approach speed
    the collision was run at: linear in it)."""

    restitution: float
    touch_duration: float
    steps: int
    peak_penetration: float

    def to_json(self) -> dict:
        """The four fields by name (SI)."""
        return {"restitution": self.restitution, "touch_duration": self.touch_duration,
                "steps": self.steps, "peak_penetration": self.peak_penetration}


#: Largest energy-ledger error (fraction of the input energy) a result may carry: every rung's
#: own tolerance is below 2 % (compare/runs/tolerances.toml [ledger]); beyond this it diverged.
LEDGER_DIVERGED = 0.05


def check_plausible(result: SimulationResult) -> SimulationResult:
    """``result`` if its numbers can be reported, else :class:`SimulationDiverged` naming the
    check that failed, in one line:

    * x_max finite and positive, impact loss finite, the energy ledger
      finite and at most :data:`LEDGER_DIVERGED` of the input;
    * no energy beyond the input: the energy delivered, the rebound energy and the contact's
      dissipation each in [-tol, 1 + tol] x 0.5 m u_1^2 (tol: :data:`LEDGER_DIVERGED`), and
      no negative dissipation beyond the run's own ledger error (a contact cannot create
      energy);
    * times within the run: T0, t_xmax, t_sep and the first contact in [0, its end].

    A run that passes them with x_max beyond the clamp height a raises
    :class:`OutsideValidity` instead (the small-deflection beam of eq 1 cannot move further
    than a: the model's validity failed, not the solver); a run cut short by t_end
    (an event at or after t_end, inside what the engine simulated) a ParameterError naming
    --t-end."""
    m = result.metrics
    model, scen = result.model or {}, result.scenario or {}
    a = (scen.get("trunk") or {}).get("clamp_height", math.inf)
    x_max, loss, ledger = m.get("x_max"), m.get("impact_loss"), m.get("ledger_residual")
    problem = None
    if not finite_number(x_max) or not 0.0 < x_max:
        problem = f"x_max = {x_max!r} m (allowed (0, a = {a:g}] m: the clamp height)"
    elif not finite_number(loss):
        problem = f"impact_loss = {loss!r} J"
    elif not finite_number(ledger) or ledger > LEDGER_DIVERGED:
        problem = (f"energy ledger residual {ledger!r} of the input energy (allowed up to "
                   f"{LEDGER_DIVERGED:g})")
    else:
        problem = _energy_problem(m, model, ledger) or _time_problem(
            m, scen.get("t_end"), model.get("dt"), _record_end(result))
    if problem is not None:
        raise SimulationDiverged(f"{result.backend}: {problem}")
    if x_max > a:  # a sound run (ledger and energies hold) that the beam cannot represent
        raise OutsideValidity(
            f"{result.backend}: x_max = {x_max:.4g} m beyond the clamp height a = {a:g} m: "
            "the small-deflection trunk of eq 1 cannot move that far (a stiffer or heavier "
            "tree, or a lighter or slower pendulum, stays within it)")
    short = _truncation_problem(m, scen.get("t_end"), model.get("dt"))
    if short is not None:
        raise ParameterError(f"--t-end = {scen['t_end']:.4g} s is too short for this run "
                             f"({result.backend}): {short}: a longer --t-end")
    return result


#: A peak this close to the run's end (fraction of t_end) is the run's end, not a peak.
AT_THE_END = 1e-3


def _truncation_problem(m: dict, t_end, dt=None) -> str | None:
    """What a run cut short by t_end cannot report, or None: a time after t_end
    (:func:`_beyond_end`; ``dt`` the run's step, s), x_max still rising at the end (its
    peak lies beyond), or the bodies still in contact (the energies need the last
    separation)."""
    if not finite_number(t_end):
        return None
    beyond = _beyond_end(m, t_end, dt)
    if beyond is not None:
        return beyond
    t_xmax = m.get("t_xmax")
    if finite_number(t_xmax) and t_xmax >= t_end * (1.0 - AT_THE_END):
        return f"the trunk is still moving out at the end (t_xmax = {t_xmax:.4g} s)"
    if "energy_delivered" in m and not finite_number(m.get("energy_delivered")):
        return "the bodies are still in contact at the end (energy_delivered needs the last " \
               "separation)"
    return None


def _energy_problem(m: dict, model: dict, ledger: float) -> str | None:
    """An energy beyond the input, or a contact that created energy, or None."""
    mass, u1 = model.get("m"), model.get("u1")
    if not (finite_number(mass) and finite_number(u1)):
        return None
    e0 = 0.5 * mass * u1 ** 2
    for key in ("energy_delivered", "rebound_energy", "contact_dissipation"):
        v = m.get(key)
        if finite_number(v) and not -LEDGER_DIVERGED * e0 <= v <= (1 + LEDGER_DIVERGED) * e0:
            return (f"{key} = {v:.4g} J beyond the input energy {e0:.4g} J (allowed "
                    f"[{-LEDGER_DIVERGED:g}, {1 + LEDGER_DIVERGED:g}] of it)")
    for key in ("contact_dissipation", "impact_loss"):
        v = m.get(key)
        if finite_number(v) and v < -(ledger + 1e-9) * e0:
            return (f"{key} = {v:.4g} J < 0 beyond the run's energy ledger error "
                    f"({ledger:.2g} of {e0:.4g} J): the contact created energy")
    return None


TIME_SLACK = 0.01
"""Times may pass t_end by this fraction of it, or by two time steps where that is more: an
engine's last step ends past t_end by up to one step and its t = 0, the touch, lies inside a
step (MuJoCo's SDOF at dt = 5.9 us over a 0.2 ms run: 3 %); a gross error is far beyond.
A time past t_end inside what an engine simulated (MuJoCo's full pendulum runs past it), or
a peak in the last step, is the run's end: a t_end too short (:func:`_truncation_problem`),
not a divergence."""


#: The metrics that are times after the first touch (s), each inside [0, t_end].
TIME_KEYS = tuple(m.name for m in METRICS if m.unit == "s")


def _time_problem(m: dict, t_end, dt=None, span=None) -> str | None:
    """A time before the first touch or after the run's ``span`` (s: the end of what was
    simulated after the touch, default ``t_end``; beyond :func:`_slack`), or None."""
    if not finite_number(t_end):
        return None
    end = max(t_end, span if finite_number(span) else t_end) + _slack(t_end, dt)
    for key in TIME_KEYS:
        v = m.get(key)
        if finite_number(v) and not 0.0 <= v <= end:
            return (f"{key} = {v:.4g} s outside the run [0, t_end = {t_end:.4g}] s (a longer "
                    "--t-end: the peak or the separation lies beyond it)")
    return None


def _slack(t_end: float, dt=None) -> float:
    """How far (s) a time may pass t_end: :data:`TIME_SLACK` of it or two steps ``dt``."""
    return max(TIME_SLACK * t_end, 2.0 * dt if finite_number(dt) and dt > 0 else 0.0)


def _record_end(result) -> float | None:
    """The last time of ``result``'s record (s after the touch) when it is sampled already
    (an engine's: MuJoCo's full pendulum simulates past t_end), else None (never sampled
    here: a deferred record stays unpaid)."""
    record = result.record
    if record is None or "t" not in record.__dict__ or not len(record.t):
        return None
    return float(record.t[-1])


def _beyond_end(m: dict, t_end, dt=None) -> str | None:
    """A time after ``t_end`` (beyond :data:`TIME_SLACK` of it or two steps ``dt``, s,
    whichever is more: an engine that simulates past t_end, as MuJoCo's full pendulum's
    swing does, found its event there), or None: a t_end too short for the event."""
    slack = _slack(t_end, dt)
    for key in TIME_KEYS:
        v = m.get(key)
        if finite_number(v) and v > t_end + slack:
            return f"{key} = {v:.4g} s lies after t_end"
    return None


def finite_number(v) -> bool:
    """True when ``v`` is a finite real number (Python or numpy; not a bool, None or a
    string)."""
    return (isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)
            and math.isfinite(v))


def to_jsonable(obj):
    """JSON-safe copy of ``obj``, the one converter every JSON writer uses (through
    :func:`json_text`): dicts (keys as text), lists, tuples and arrays as lists; Python and
    numpy booleans, integers and floats as Python's; NaN and inf as None (strict JSON has
    neither); an enum as its value, a dataclass as its fields, a path as its text. Raises
    TypeError naming the type of anything else."""
    if isinstance(obj, (str, type(None))) and not isinstance(obj, enum.Enum):
        return obj
    if isinstance(obj, dict):
        return {_json_key(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [to_jsonable(v) for v in obj]
    return _json_scalar(obj)


def _json_scalar(obj):
    """The JSON form of one non-container value (:func:`to_jsonable`)."""
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, enum.Enum):
        return to_jsonable(obj.value)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return to_jsonable({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)})
    if isinstance(obj, PurePath):
        return str(obj)
    raise TypeError(f"{type(obj).__name__} has no JSON form (analytic.results.to_jsonable)")


def _json_key(key) -> str:
    """A dict key as JSON text: a string as it is, an enum by its value, a number or
    boolean as JSON writes it."""
    if isinstance(key, str) and not isinstance(key, enum.Enum):
        return key
    value = _json_scalar(key)
    return value if isinstance(value, str) else json.dumps(value)


def json_text(obj, **options) -> str:
    """``obj`` as strict JSON text (:func:`to_jsonable`, then ``json.dumps`` with
    ``allow_nan=False``: never a NaN or Infinity token); ``options`` are json.dumps's
    (indent, sort_keys, separators)."""
    return json.dumps(to_jsonable(obj), allow_nan=False, **options)
