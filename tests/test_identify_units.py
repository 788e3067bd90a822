"""A declared unit the record contradicts is refused for every column (issue 54 item 4): x
(the existing check), the pendulum's y (it swings within its release chord of the contact
and spans at least its approach), t switching units part-way (its step changing by a unit's
factor); and a fitted value at its range's end (t0 within a sample of it) is never
"determined"."""

from __future__ import annotations

import math

import numpy as np
import pytest

from treeimpact.analytic.identify.diagnosis import DiagnosisKind
from treeimpact.analytic.identify.fit_parameters import Slot, record_parameters
from treeimpact.analytic.identify.pendulum_record import read_record
from treeimpact.analytic.identify.record_features import mixed_time_unit
from treeimpact.analytic.identify.record_fit import Record, at_range_end, fit_record
from treeimpact.compare.interface.cli import main
from treeimpact.compare.runs.exits import ExitCode

from test_record_fit import ARGS, synthetic


def write(path, header: str, *columns) -> str:
    rows = zip(*columns)
    path.write_text(header + "\n" + "".join(",".join(f"{v:.9g}" for v in r) + "\n"
                                            for r in rows))
    return str(path)


def refused_for_units(fit, words: str) -> None:
    assert not fit.explained and not fit.conclusion.fitted
    assert fit.diagnosis_kinds() == [DiagnosisKind.UNITS]
    assert words in fit.diagnoses[0].message, fit.diagnoses[0].message
    assert not any(fit.determined.values())


def test_y_declared_in_m_holding_mm_is_refused_like_x(tmp_path, capsys):
    """The issue's record: y [m] holding mm (34 m of pendulum travel, beyond its 0.94 m
    release chord) was fitted, y_offset 2.14 m "determined"; now refused naming y and mm,
    exit 4, one stderr line; declared as mm the same numbers are fitted and explained."""
    _, record, test = synthetic(0.1, 0, pendulum=True)
    wrong = write(tmp_path / "y-mm.csv", "t [s],x [m],y [m]", record.t, record.x,
                  1e3 * record.y)
    refused_for_units(fit_record(read_record(wrong), test), "y looks like mm, not m")
    assert main(["identify", wrong, *ARGS]) == ExitCode.NOT_ACHIEVED
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "y looks like mm" in err and "'y (mm)'" in err
    right = write(tmp_path / "y-declared.csv", "t [s],x [m],y [mm]", record.t, record.x,
                  1e3 * record.y)
    fit = fit_record(read_record(right), test)
    assert fit.explained and fit.determined["M_T"]
    assert abs(fit.values["y_offset"] - 0.003) < 1e-3  # the synthetic record's 3 mm offset


def test_x_declared_in_m_holding_mm_is_still_refused(tmp_path):
    _, record, test = synthetic(0.1, 0)
    path = write(tmp_path / "x-mm.csv", "t [s],x [m]", record.t, 1e3 * record.x)
    refused_for_units(fit_record(read_record(path), test), "x looks like mm, not m")


def test_y_declared_in_mm_holding_m_is_refused(tmp_path):
    """1000 x too small: y spans less than its own approach over the 10 ms of rest
    (u_1 T / pi = 7.6 mm)."""
    _, record, test = synthetic(0.1, 0, pendulum=True)
    path = write(tmp_path / "y-m.csv", "t [s],x [m],y [mm]", record.t, record.x, record.y)
    refused_for_units(fit_record(read_record(path), test), "y looks like m, not mm")


def test_a_time_column_switching_to_ms_halfway_is_refused(tmp_path, capsys):
    """The issue's record (K_T, C_T and E fitted before): the step goes from 0.2 ms to
    0.2 "s" at the switch; refused naming the row where it changes, exit 4."""
    _, record, test = synthetic(0.1, 0)
    t = record.t.copy()
    t[250:] *= 1e3  # from sample 250 on the logger writes ms
    assert mixed_time_unit(t) == 250
    refused_for_units(fit_record(Record(t, record.x), test), "row 252")
    path = write(tmp_path / "t-mixed.csv", "t [s],x [m]", t, record.x)
    assert main(["identify", path, *ARGS]) == ExitCode.NOT_ACHIEVED
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "t's step changes" in err and "row 252" in err  # the
    # file's line: the header is line 1, sample 250 line 252


@pytest.mark.parametrize("steps", [
    np.full(500, 2e-4),  # a clean clock
    2e-4 * (1.0 + 0.05 * np.random.default_rng(1).standard_normal(500)),  # 5 % jitter
    np.r_[np.full(250, 2e-4), [2e-3], np.full(249, 2e-4)],  # ten samples lost once
    np.r_[np.full(250, 2e-4), np.full(250, 5e-4)],  # a rate changed 2.5 x
])
def test_a_clock_in_one_unit_is_not_mixed(steps):
    assert mixed_time_unit(np.r_[0.0, np.cumsum(steps)]) is None


def test_a_t0_within_a_sample_of_its_range_end_is_not_determined():
    """t0's range is [t_0 - 10 dt, t_end - 10 dt]; a fit half a sample from either end
    ends there (optimiser_trouble reads it so), not at the record's contact."""
    t = np.arange(0.0, 0.1, 2e-4)
    params = record_parameters(t, 2e-4, [0.01], restitution_given=False, pendulum=False)
    p = np.zeros(len(Slot))
    p[Slot.LN_DYNAMIC_MASS], p[Slot.LN_EQUIVALENT_STIFFNESS], p[Slot.TRUNK_DAMPING_RATIO] = (
        math.log(100.0), 14.0, 0.1)
    p[Slot.RESTITUTION] = 0.1
    for t0, ends in ((params[Slot.T0].low + 1e-4, True), (params[Slot.T0].high - 1e-4, True),
                     (0.01, False)):
        p[Slot.T0] = t0
        assert ("t0" in at_range_end(p, params)) is ends, t0


def test_records_in_their_declared_units_pass(tmp_path):
    """The synthetic records with the pendulum's y (offset 3 mm) and without, as written
    and read back: no unit line, fitted and explained."""
    _, record, test = synthetic(0.1, 1, pendulum=True)
    path = write(tmp_path / "ok.csv", "t [ms],x [mm],y [mm]", 1e3 * record.t, 1e3 * record.x,
                 1e3 * record.y)
    fit = fit_record(read_record(path), test)
    assert fit.explained and DiagnosisKind.UNITS not in fit.diagnosis_kinds()


def test_a_length_column_switching_to_mm_halfway_is_refused(tmp_path, capsys):
    """x in m, then mm from sample 250 (the logger's unit changed): one step of ~1000 x
    the value, no other step within a twentieth of it, the level after it 1000 x the level
    before: refused naming the row, exit 4; y the same."""
    from treeimpact.analytic.identify.record_features import mixed_length_unit

    _, record, test = synthetic(0.1, 0, pendulum=True)
    x = record.x.copy()
    x[250:] *= 1e3
    row, factor = mixed_length_unit(x)
    assert row == 250 and 500 < factor < 2000  # the level's ratio, a unit factor 1000
    refused_for_units(fit_record(Record(record.t, x), test), "row 252")
    path = write(tmp_path / "x-mixed.csv", "t [s],x [m]", record.t, x)
    assert main(["identify", path, *ARGS]) == ExitCode.NOT_ACHIEVED
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "x's values change by a factor" in err and "row 252" in err
    y = record.y.copy()
    k = 50 + int(np.argmax(np.abs(y[50:-50])))  # where it shows (near 0: within the noise)
    y[k:] *= 1e-2  # cm -> m the other way
    assert mixed_length_unit(y)[0] == k


def test_a_length_column_in_one_unit_is_not_mixed():
    """A struck trunk's record (its first velocity jump included), one outlier spike of
    50 x the motion, and the noisy records: no switch found."""
    from treeimpact.analytic.identify.record_features import mixed_length_unit

    for seed, noise in ((0, 0.0), (1, None), (2, 0.05)):  # clean, the default noise, 5 %
        _, record, _ = synthetic(0.1, seed, pendulum=True, noise=noise)
        assert mixed_length_unit(record.x) is None and mixed_length_unit(record.y) is None
    _, record, _ = synthetic(0.1, 0, noise=0.0)
    spiked = record.x.copy()
    spiked[300] += 50 * float(np.ptp(record.x))
    assert mixed_length_unit(spiked) is None
