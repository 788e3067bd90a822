"""The report's record fits: the exact 1-DOF model fitted to each rung's whole record, sampled
and noised as a field test records it (analytic.identify.record_fit): the 1-DOF properties
that best explain it, their errors against the truth, and whether the 1-DOF model explains
the record at all. SI units; docs/identification.md."""

from __future__ import annotations

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.identify.procedure import pendulum_test_of
from treeimpact.analytic.model.parameters import Pendulum
from treeimpact.analytic.model.two_body import two_body_model

from .ident_records import sampled_record

#: Sampling of the records handed to the full-record fit (Hz), and the rest prepended (s) so
#: the fit sees the trunk still before the contact, as in a measured record.
FIT_RATE = 5000.0
FIT_REST = 0.02  # s of rest before the impact: the fit estimates the sensor's noise there
#: Gaussian noise added to each rung's record (fraction of its peak, seed 0), the study's: a
#: record is "explained" when the fit's residual is at the level of its noise, and a
#: noise-free record would call the pad's 0.02 % of the peak a misfit (issue 24's fit).
FIT_NOISE = 0.01


def fit_tasks(ladder) -> list[tuple]:
    """One task per rung of ``ladder`` (a built compare.tree.ladder.Ladder) with a record, for
    :func:`fit_one`: (rung id, t (s), x (m) sampled at FIT_RATE with FIT_NOISE, the pendulum
    test, the true M_T (kg), K_T (N/m), C_T (N s/m) of the two-body model, eqs 7-11); none
    when the ladder's impactor is not a pendulum."""
    scen = ladder.scenario
    if not isinstance(scen.impactor, Pendulum):
        return []
    model = two_body_model(scen)
    truth = {"M_T": model.dynamic_mass, "K_T": model.equivalent_stiffness,
             "C_T": model.equivalent_damping}
    test = pendulum_test_of(scen)
    return [(r.rung.id, *sampled_record(r.result.trajectory, FIT_RATE, noise=FIT_NOISE,
                                        rest=FIT_REST), test, truth)
            for r in ladder.rungs if r.ok and r.result.trajectory is not None]


def fit_one(task: tuple) -> dict:
    """The exact 1-DOF model fitted to one rung's whole record (a :func:`fit_tasks` task): the
    1-DOF properties that best explain it, their errors against the model's truth, and
    whether the 1-DOF model explains the record at all (analytic.identify.record_fit)."""
    # lazy: +679 ms at import otherwise (scipy, numpy),
    # which this module's other callers do not need
    from treeimpact.analytic.identify.record_fit import Record, fit_record

    rung, t, x, test, truth = task
    try:
        fit = fit_record(Record(t, x), test)
    except ParameterError as exc:
        return {"rung": rung, "error": str(exc)}
    keys = (*truth, "restitution")
    return {"rung": rung, "values": {k: fit.values[k] for k in keys},
            "errors": {k: fit.values[k] / v - 1.0 for k, v in truth.items()},
            "ranges": {k: fit.intervals[k] for k in keys
                       if not fit.determined[k]},  # a one-impact record: ranges
            "intervals": {k: fit.intervals[k] for k in keys},  # 95 %
            "residual": fit.residual_rms / fit.peak, "explained": fit.explained}
