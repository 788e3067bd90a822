"""identify is never more certain than its record (issue 41 item 6): a second basin in e and
M_T that explains the record within the joint 95 % threshold widens the intervals, and a
value at an end of the fit's range is never "determined"."""

from __future__ import annotations

import math

import numpy as np
import treeimpact as ti
from treeimpact.analytic.identify.fit_parameters import E_MAX, M_RANGE, Slot, record_parameters
from treeimpact.analytic.identify.record_fit import at_range_end, fit_record
from treeimpact.compare.interface.api_records import pendulum_test


def test_a_parameter_at_its_range_s_end_leaves_what_it_moves_undetermined():
    """M_T at the fit's upper bound (1e5 kg) is no tree's value: M_T and what it moves are
    named; e = 0 is a physical value (a plastic pad), e at E_MAX is the range's end."""
    params = record_parameters(np.linspace(0.0, 0.1, 101), 1e-3, [0.01],
                               restitution_given=False, pendulum=False)
    p = np.zeros(len(Slot))
    p[Slot.LN_DYNAMIC_MASS], p[Slot.LN_EQUIVALENT_STIFFNESS], p[Slot.TRUNK_DAMPING_RATIO] = (
        math.log(110.0), 14.0, 0.1)
    p[Slot.T0] = 0.02
    assert at_range_end(p, params) == set()  # e = 0: physical
    p[Slot.LN_DYNAMIC_MASS] = math.log(M_RANGE[1])
    assert {"M_T", "C_T", "omega_1", "V_1"} <= at_range_end(p, params)
    p[Slot.LN_DYNAMIC_MASS], p[Slot.RESTITUTION] = math.log(110.0), E_MAX
    assert at_range_end(p, params) == {"restitution", "V_1"}
    assert at_range_end(p, params.freeze(Slot.RESTITUTION)) == set()  # e given: held


def test_a_second_basin_widens_m_t_to_cover_the_truth():
    """The fuzzer's record (central-leader, 5 kHz, 20 % noise, seed 7): the free fit lands in
    a basin at e = 0.54, M_T = 244 kg [209, 272] "determined", while e = 0.1 (M_T 123 kg
    [105, 143], the truth 110 kg, e 0.1) explains it within Delta chi^2 = 9.7 of it: beyond
    one parameter's 3.84, inside the joint threshold of the 5 fitted (11.07). Now M_T is not
    fixed, its range covering both basins and the truth, and e's range covers 0.1."""
    sim = ti.simulate("central-leader")
    record = ti.record_from_simulation(sim, noise=0.2, seed=7)
    fit = fit_record(record, pendulum_test(sim.scenario, None, None))
    lo, hi = fit.intervals["M_T"]
    assert not fit.determined["M_T"] and math.isnan(fit.values["M_T"])
    assert lo <= 123.0 and hi >= 244.0 and lo <= 110.0 * 1.1  # both basins; the truth near
    e_lo, e_hi = fit.intervals["restitution"]
    assert e_lo <= 0.1 <= e_hi and e_hi >= 0.54


def test_a_rest_the_noise_hid_is_not_called_absent():
    """The fuzzer's seed 6 (20 % noise): the record's shape reads the contact at its first
    sample, while the fit puts it 20 ms in (the record's 20 ms of rest); the diagnosis said
    "the record has no rest before the contact" and now says the noise hid it."""
    sim = ti.simulate("central-leader")
    record = ti.record_from_simulation(sim, noise=0.2, seed=6)
    fit = fit_record(record, pendulum_test(sim.scenario, None, None))
    held = [d.message for d in fit.diagnoses if d.kind.value == "sensor-held"]
    assert held and "has no rest before the contact" not in held[0]
    assert "the noise hides it" in held[0] and 0.019 < fit.values["t0"] < 0.023


def test_a_record_declared_in_cm_that_is_in_m_is_refused():
    """The fuzzer's 1 % record (x in m) read with --length-unit cm: a trunk moving at 0.0108
    m/s after a 132 kg pendulum at 2.4 m/s is a dynamic mass of 3e4 kg (eq 21), beyond any
    tree a pendulum tests (M_PLAUSIBLE, 1e4 kg): it was fitted (M_T = 23,560 kg); now it is
    refused for its units, naming the unit that reads it right."""
    from treeimpact.analytic.identify.pendulum_record import Record

    sim = ti.simulate("central-leader")
    rec = ti.record_from_simulation(sim, noise=0.01, seed=1)
    wrong = Record(t=rec.t, x=rec.x * 1e-2, length_unit="cm")  # its numbers read as cm
    fit = fit_record(wrong, pendulum_test(sim.scenario, None, None))
    assert not fit.conclusion.fitted and "x looks like m, not cm" in fit.warnings[0]
    assert fit_record(rec, pendulum_test(sim.scenario, None, None)).conclusion.fitted
