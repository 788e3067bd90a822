"""The public API's records and identification (re-exported by :mod:`treeimpact`;
docs/api.md, "Identification from a record"): a pendulum-test record read or made from a
run, the test it records, and the tree identified from it. SI units."""

from __future__ import annotations

import math
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.identify.pendulum_record import Record
from treeimpact.analytic.identify.pendulum_record import read_record as read
from treeimpact.analytic.identify.procedure import READINGS, PendulumTest, procedure_readings
from treeimpact.analytic.model.parameters import Pendulum, Scenario, check_range
from treeimpact.analytic.model.plausible import implausible_values, warn_implausible
from treeimpact.analytic.model.registry import BY_NAME

from ..runs.names import NAMING, show
from ..runs.recording import check_sampling, sample
from .api_call import api_function
from .api_results import Identification, Simulation, identification_of


@api_function
def read_record(path, *, time_unit: str | None = None, length_unit: str | None = None):
    """A pendulum-test record read from a CSV file (docs/identification.md, "The record").

    Args:
        path: the file: a header naming the columns t, x and optionally y (the pendulum's),
            any order, units in the header ('t [ms]', 'x (mm)').
        time_unit: the unit of a time column whose header names none: s (default), ms, us.
        length_unit: that of x and y: m (default), cm, mm, um.

    Returns:
        :class:`Record`: times (s, from the first sample) and displacements (m).

    Raises:
        ParameterError: an unreadable file, a malformed header or row (named by its line).
    """
    return read(path, time_unit=time_unit, length_unit=length_unit)


@api_function
def record_from_simulation(simulation: Simulation, *, rate_hz: float = 5000.0,
                           noise: float = 0.0, seed: int = 0):
    """A run as a field test records it (what ``treeimpact simulate --record`` writes).

    Args:
        simulation: a :func:`simulate` result.
        rate_hz: the sampling rate, Hz, in [50, 1e6] (default 5000, as the command's).
        noise: Gaussian noise as a fraction of the peak, in [0, 0.5] (default 0).
        seed: the noise's seed, an integer >= 0 (default 0).

    Returns:
        :class:`Record`: the trunk's displacement x (m) from 20 ms before the impact, times
        t (s) from the first sample.

    Raises:
        ParameterError: a rate, noise or seed out of range, or a backend without a
            trajectory.
    """
    check_sampling(rate_hz, noise, seed, names=("rate_hz", "noise", "seed"))
    t, x = sample(simulation.result, rate_hz, noise, seed)
    return Record(t=t, x=x, source=f"{simulation.scenario.name} ({simulation.backend})")


def checked_input(name: str, value) -> float:
    """``value`` of the registry's input ``name`` (analytic.model.registry) as a float, or a
    one-line ParameterError naming it as typed (the flag while a command runs, else the
    keyword) with its allowed range: the one check of a value entering here."""
    p = BY_NAME[name]
    return check_range(show(name, NAMING.get()), value, low=p.low, high=p.high,
                       unit="" if p.unit == "1" else p.unit)


def pendulum_test(test, clamp_height, diameter):
    """The identification's PendulumTest (analytic.identify.procedure) of ``test``: a
    Scenario (its pendulum, its trunk's clamp height and diameter), or a Pendulum with the
    ``clamp_height`` a and ``diameter`` d (m) it struck; each checked against its range
    (ParameterError naming it). Shared by :func:`identify` and ``treeimpact identify``."""
    if isinstance(test, Scenario):
        if clamp_height is not None or diameter is not None:
            raise ParameterError("clamp_height, diameter: the scenario's trunk gives them; "
                                 "pass them only with a Pendulum")
        pend, clamp_height, diameter = (test.impactor, test.trunk.clamp_height,
                                        test.trunk.diameter)
    else:
        pend = test
    if not isinstance(pend, Pendulum):
        raise ParameterError(f"test: expected a Scenario or a Pendulum, got "
                             f"{type(pend).__name__} (the identification needs a pendulum)")
    for name, value in (("clamp_height", clamp_height), ("diameter", diameter)):
        if value is None:
            raise ParameterError(f"{name}: required with a Pendulum (m)")
        checked_input(name, value)
    if not isinstance(test, Scenario):  # a scenario warned where it was read
        warn_implausible(implausible_values({
            "impactor.mass": pend.mass, "impactor.equivalent_length": pend.equivalent_length,
            "impactor.release_angle_deg": pend.release_angle_deg, "impactor.gravity":
            pend.gravity, "trunk.clamp_height": clamp_height, "trunk.diameter": diameter}))
    return PendulumTest(impactor_mass=pend.mass, equivalent_length=pend.equivalent_length,
                        release_angle=pend.release_angle_rad, clamp_height=clamp_height,
                        diameter=diameter, gravity=pend.gravity)


@api_function
def identify(record, test, *, clamp_height: float | None = None,
             diameter: float | None = None, restitution: float | None = None,
             time_unit: str | None = None, length_unit: str | None = None,
             plot=None) -> Identification:
    """Tree properties from a pendulum-test record: the exact 1-DOF model fitted to every
    sample (docs/identification.md) beside the paper's procedure, as ``treeimpact
    identify``.

    Args:
        record: a :class:`Record` (:func:`read_record`, :func:`record_from_simulation`) or
            the path of a record file.
        test: the test's :class:`Scenario` (its pendulum, clamp height and diameter) or its
            :class:`Pendulum`.
        clamp_height: the impact height a, m (with a Pendulum only).
        diameter: the trunk's diameter d, m (with a Pendulum only).
        restitution: the pad's e in [0, 1] if known, held fixed (default: fitted).
        time_unit: a record file's time unit where its header names none: s (default), ms,
            us (as :func:`read_record`).
        length_unit: its x and y unit likewise: m (default), cm, mm, um.
        plot: a file (.png, .pdf or .svg) to draw the record, both fits and the residuals
            in (default: none; none drawn for a record not fitted).

    Returns:
        :class:`Identification`: M_T (kg), K_T (N/m), C_T (N s/m), the damping ratios, e,
        E (Pa), each an :class:`Estimate` with its 95 % interval, the verdict, and the
        paper's procedure's readings.

    Raises:
        ParameterError: an unreadable record, a test that is not a pendulum's, a value out
            of its range, a plot that is not a file of those formats.
    """
    # lazy: +643 ms at import otherwise (scipy, numpy),
    # which this module's other callers do not need
    from treeimpact.analytic.identify.record_fit import fit_record

    the_test = pendulum_test(test, clamp_height, diameter)
    if restitution is not None:
        checked_input("restitution", restitution)
    if plot is not None:
        _check_plot_path(plot)
    if isinstance(record, (str, Path)):
        record = read(record, time_unit=time_unit, length_unit=length_unit)
    if not isinstance(record, Record):
        raise ParameterError(f"record: expected a Record or a path, got "
                             f"{type(record).__name__}")
    fit = fit_record(record, the_test, restitution=restitution)
    procedure = _procedure(record, the_test, fit)
    if plot is not None and math.isfinite(fit.residual_rms):
        # lazy: +400 ms at import otherwise (matplotlib), which only a plot needs
        from ..tree.record_figure import draw_record_fit

        draw_record_fit(plot, record, fit, procedure, the_test)
    return identification_of(fit, record, procedure)


def _procedure(record, test, fit) -> dict:
    """The paper's procedure's readings of ``record`` (analytic.identify.procedure), or for
    a record the ``fit`` did not fit (its units, no impact: every method refuses it) each
    reading's error saying why."""
    if not fit.conclusion.fitted:
        return {reading: {"error": f"not read: {fit.findings()}"} for reading in READINGS}
    return procedure_readings(record.t, record.x, test, y=record.y)


def _check_plot_path(path) -> None:
    """``plot`` names a file of a format it writes, not a directory (one line naming it as
    typed, before the fit)."""
    # lazy: the figure's module (matplotlib on use only), which only a plot needs
    from ..tree.record_figure import PLOT_FORMATS

    p, flag = Path(path), show("plot", NAMING.get())
    if p.is_dir():
        raise ParameterError(f"{flag} {str(path)!r} is a directory: name a file in it, e.g. "
                             f"{str(p / 'fit.png')!r}")
    if p.suffix.lower() not in PLOT_FORMATS:
        raise ParameterError(f"{flag} {str(path)!r}: allowed a file ending in "
                             f"{', '.join(PLOT_FORMATS)}")


__all__ = ["checked_input", "identify", "pendulum_test", "read_record", "record_from_simulation"]
