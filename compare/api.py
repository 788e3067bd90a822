"""The public API re-exported by :mod:`treeimpact` (docs/api.md): one function per job, in SI
units, each a thin call into the module that does the work.

Bad input raises :class:`treeimpact.ParameterError` (one line naming the field and its
range); a run with no numbers to report raises :class:`treeimpact.SimulationDiverged`.
"""

from __future__ import annotations

from pathlib import Path

from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.results import SimulationResult


def simulate(scenario, backend: str = "analytic", **options) -> SimulationResult:
    """One run of ``scenario`` (a :class:`Scenario`, shipped name or TOML path) on
    ``backend`` (``analytic``, ``soft``, ``beam``, ``mujoco``, ``bullet``; :func:`backends`),
    with the backend's own options (e.g. ``restitution``, ``t_end`` s, ``trunk="chain"``,
    ``segments``); the result is checked for plausibility before it is returned."""
    from .backends import get_backend
    from .runs import resolve_scenario

    return get_backend(backend).simulate(resolve_scenario(scenario), **options)


def modes(scenario, backend: str = "analytic", **options) -> dict:
    """Static stiffness at the clamp (N/m) and natural frequencies (rad/s) of the
    backend's trunk beside the continuous beam's (``{"model": ..., "beam": ...}``)."""
    from .backends import get_backend
    from .runs import resolve_scenario

    return get_backend(backend).modes(resolve_scenario(scenario), **options)


def backends() -> dict[str, str]:
    """The backends by name, with what each one is."""
    from .backends import BACKENDS

    return {name: b.description for name, b in BACKENDS.items()}


def ladder(scenario, *, engines=None, segments: int | None = None):
    """The scenario run as the discrepancy ladder (one assumption per rung, judged against
    ``compare/tolerances.toml``): a :class:`treeimpact.compare.ladder.Ladder` whose
    ``checks()`` carry the verdicts and ``table()`` every rung's values."""
    from .backends import ENGINES
    from .ladder import build_ladder

    return build_ladder(scenario, engines=ENGINES if engines is None else tuple(engines),
                        segments=segments)


def sweep(scenario, grid, out, *, backends=("analytic",), ladder: bool = False,
          options: dict | None = None, workers: int | None = None):
    """A parameter sweep (``grid``: specs such as ``["restitution=0.05:0.5:10"]``) into the
    directory ``out``, resumable; returns the :class:`treeimpact.compare.sweep.SweepResult`
    (its ``table`` a pandas DataFrame, one row per grid point and backend)."""
    from .sweep.run import run_sweep

    return run_sweep(scenario, grid, out, backends=backends, ladder=ladder, options=options,
                     workers=workers, progress=False)


def read_record(path, *, time_unit: str | None = None, length_unit: str | None = None):
    """A pendulum-test record: a CSV file with columns t, x (and y, the pendulum's) named in
    its header, units there ('t [ms]', 'x (mm)') or given here (default s, m); converted
    to SI, times from the first sample (docs/identification.md, "The record")."""
    from treeimpact.analytic.identify.pendulum_record import read_record as read

    return read(path, time_unit=time_unit, length_unit=length_unit)


def identify(record, *, mass: float, equivalent_length: float, release_angle_deg: float,
             clamp_height: float, diameter: float, restitution: float | None = None):
    """Tree properties (M_T kg, K_T N/m, C_T N s/m, xi, e, E Pa, with 95 % intervals) from a
    record (a path, read in s and m unless its header says otherwise, or
    :func:`read_record`'s result) by the whole-record fit of the exact 1-DOF model, with
    its verdict and diagnoses; ``restitution``: the pad's e if known, held fixed."""
    import math

    from treeimpact.analytic.identify.procedure import PendulumTest
    from treeimpact.analytic.identify.record_fit import fit_record
    from treeimpact.analytic.model.parameters import Pendulum

    if isinstance(record, (str, Path)):
        record = read_record(record)
    pend = Pendulum(mass=mass, equivalent_length=equivalent_length,
                    release_angle=math.radians(release_angle_deg))
    test = PendulumTest(impactor_mass=pend.mass, equivalent_length=pend.equivalent_length,
                        release_angle=pend.release_angle, clamp_height=clamp_height,
                        diameter=diameter, gravity=pend.gravity)
    return fit_record(record, test, restitution=restitution)


def report(out, scenarios=None, *, studies=()) -> dict:
    """Write the discrepancy report (report.html, report.md, report.json) into ``out`` for
    ``scenarios`` (default: the shipped ones) and finished ``studies`` (sweep directories);
    returns the written paths by kind."""
    from .report import write_report
    from .runs import resolve_scenario

    scens = None if scenarios is None else [resolve_scenario(s) for s in scenarios]
    return write_report(out, scenarios=scens, study_dirs=tuple(studies))


__all__ = ["Scenario", "SimulationResult", "backends", "identify", "ladder", "modes",
           "read_record", "report", "simulate", "sweep"]
