"""The public API's records and identification (re-exported by :mod:`treeimpact`;
docs/api.md, "Identification from a record"): a pendulum-test record read or made from a
run, the test it records, and the tree identified from it. SI units."""

from __future__ import annotations

from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.identify.pendulum_record import Record
from treeimpact.analytic.identify.pendulum_record import read_record as read
from treeimpact.analytic.identify.procedure import PendulumTest
from treeimpact.analytic.model.parameters import LIMITS, Pendulum, Scenario, check_range
from treeimpact.analytic.model.plausible import implausible_values, warn_implausible

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
        low, high, unit = LIMITS[f"trunk.{name}"]
        check_range(name, value, low=low, high=high, unit=unit)
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
             diameter: float | None = None, restitution: float | None = None
             ) -> Identification:
    """Tree properties from a pendulum-test record: the exact 1-DOF model fitted to every
    sample (docs/identification.md), as ``treeimpact identify``.

    Args:
        record: a :class:`Record` (:func:`read_record`, :func:`record_from_simulation`) or
            the path of a record file (read in s and m unless its header says otherwise).
        test: the test's :class:`Scenario` (its pendulum, clamp height and diameter) or its
            :class:`Pendulum`.
        clamp_height: the impact height a, m (with a Pendulum only).
        diameter: the trunk's diameter d, m (with a Pendulum only).
        restitution: the pad's e in [0, 1] if known, held fixed (default: fitted).

    Returns:
        :class:`Identification`: M_T (kg), K_T (N/m), C_T (N s/m), the damping ratios, e,
        E (Pa), each an :class:`Estimate` with its 95 % interval, and the verdict.

    Raises:
        ParameterError: an unreadable record, a test that is not a pendulum's, a value out
            of its range.
    """
    # lazy: +643 ms at import otherwise (scipy, numpy),
    # which this module's other callers do not need
    from treeimpact.analytic.identify.record_fit import fit_record


    the_test = pendulum_test(test, clamp_height, diameter)
    if isinstance(record, (str, Path)):
        record = read_record(record)
    if not isinstance(record, Record):
        raise ParameterError(f"record: expected a Record or a path, got "
                             f"{type(record).__name__}")
    if restitution is not None:
        check_range("restitution", restitution, low=0.0, high=1.0)
    return identification_of(fit_record(record, the_test, restitution=restitution),
                             record)


__all__ = ["identify", "pendulum_test", "read_record", "record_from_simulation"]
