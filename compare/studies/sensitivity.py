"""The answer with error bars: a global sensitivity study (Morris elementary effects, SALib,
with the bootstrap intervals of mu*) of every cell of the report's answer table and of the
crossing durations, over the inputs nobody measured. A measured tree keeps its measured
M_T, K_T and C_T (Table 1); what varies is how the continuum carries them (clamp mass, wood
density, root compliance, shear) and the pad (its stiffness, as its 1-DOF collision time,
and e). A tree built from its geometry (``[calibration] assumed``, analytic.model.assumed)
keeps its geometry, E and crown instead, and its assumed root spring and damping vary over
their ranges, so M_T, K_T and C_T move with them (:func:`vary`). Inputs a scenario file
lists as measured (``[calibration] measured``) are held at its values. Runs on the sweep
machinery: one sweep per tree whose points are the Morris design (``input.*`` axes), the
analysis :func:`answer_under` running the 1-DOF models and the continuum at each point.
Design notes: docs/sensitivity.md. SI units.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from treeimpact.analytic.contact.soft import simulate_soft
from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.model.options import scenario_as_run

from ..runs.cache import OK, resolve_scenario
from ..runs.verdicts import validity_tolerance
from .contact_scan import shortest_within
from .study_inputs import (
    ALL_INPUTS,
    INPUTS,
    free_inputs,
    inputs_entry,
    inputs_of,
    problem,
    ranges_of,
    vary,
)
from .study_points import complete_groups, failed_points, failure_summary, rows_of
from .sweep.grid import Design
from .sweep.run import SweepSpec


#: The outputs: the answer table's cells (continuum vs 1-DOF, relative) and the crossing
#: durations (s) from which the 1-DOF model stays within the validity tolerance.
ANSWER = ("x_max", "energy_delivered", "crown_peak", "crown_peak_acceleration", "peak_force")
CROSSING = ("x_max", "energy_delivered")
OUTPUTS = tuple(f"gap.{m}" for m in ANSWER) + tuple(f"crossing.{m}" for m in CROSSING)
#: The Morris design: grid levels and the seed of its trajectories.
LEVELS = 4
SEED = 20261125
#: The bootstrap of mu*'s confidence interval (SALib's ``mu_star_conf``): resamples and level.
RESAMPLES = 1000
CONF_LEVEL = 0.95
#: The pads the crossing durations are read on (s, log-spaced over the contact scan's range).
DURATIONS = tuple(float(d) for d in np.geomspace(2e-4, 5e-2, 8))
def _gap(one_dof: float, continuum: float) -> float:
    return (continuum - one_dof) / abs(one_dof) if one_dof and math.isfinite(one_dof) \
        else math.nan


def _answer(scen, theory: str) -> dict:
    """The answer table's gaps at one varied scenario: the continuum against the paper's
    model, or the soft 1-DOF with the same pad where Newton's impulses have none (force,
    acceleration)."""
    newton = simulate(scen, samples=2).metrics
    soft = simulate_soft(scen).metrics
    beam = simulate_beam(scen, beam_theory=theory).metrics
    return {f"gap.{m}": _gap(newton[m] if math.isfinite(newton[m]) else soft[m], beam[m])
            for m in ANSWER}


def answer_under(result, scenario, params: dict) -> dict:
    """The sweep analysis of the cheap study: at the inputs ``params`` (``input.*`` axes;
    the measured ones at the scenario's own values; the run's own result is the base
    tree's, unused) the answer table's gaps."""
    return _answer(*vary(scenario, inputs_of(scenario) | dict(params)))


answer_under.columns = tuple(f"gap.{m}" for m in ANSWER)


def answer_and_crossings(result, scenario, params: dict) -> dict:
    """:func:`answer_under` (of ``result``, ``scenario`` and ``params``) and the crossing
    durations: the shortest of :data:`DURATIONS` (s) from which every longer pad keeps the
    continuum within the validity tolerance of the soft 1-DOF model with the same pad (inf:
    none up to the longest)."""
    scen, theory = vary(scenario, inputs_of(scenario) | dict(params))
    out = _answer(scen, theory)
    gaps = {m: [] for m in CROSSING}
    for d in DURATIONS:
        s = simulate_soft(scenario_as_run(scen, {"contact_duration": d})).metrics
        b = simulate_beam(scenario_as_run(scen, {"contact_duration": d}),
                          beam_theory=theory).metrics
        for m in CROSSING:
            gaps[m].append(_gap(s[m], b[m]))
    for m in CROSSING:
        found = shortest_within(DURATIONS, gaps[m], validity_tolerance())
        out[f"crossing.{m}"] = found if found is not None else math.inf
    return out


answer_and_crossings.columns = OUTPUTS
#: The analyses' references, as the sweeps load them in a worker.
ANALYSES = {False: "treeimpact.compare.studies.sensitivity:answer_under",
            True: "treeimpact.compare.studies.sensitivity:answer_and_crossings"}


def design(trajectories: int, seed: int = SEED, names=None,
           ranges: dict | None = None) -> np.ndarray:
    """The Morris design: ``trajectories`` x (inputs + 1) points over :data:`INPUTS` (only
    ``names`` when given; over the tree's ``ranges`` when given, :func:`ranges_of`),
    trajectory after trajectory, from the random ``seed``."""
    # lazy: +285 ms at import otherwise (scipy, pandas, SALib, numpy, pyarrow),
    # which this module's other callers do not need
    from SALib.sample import morris

    return morris.sample(problem(names, ranges), trajectories, num_levels=LEVELS, seed=seed)


def sensitivity_sweep(scenario, out, trajectories: int, seed: int = SEED, *,
                      crossings: bool = False):
    """The study of one tree (``scenario``) as a sweep
    (:class:`compare.studies.sweep.run.SweepSpec`) into ``out``: the Morris design
    (:func:`design` of ``trajectories`` and ``seed``) over its free inputs
    (:func:`free_inputs`, over the tree's :func:`ranges_of`) as ``input.*`` axes,
    :func:`answer_under` (with ``crossings``, :func:`answer_and_crossings`) at each point."""
    return design_sweep(scenario, out,
                        lambda names, ranges: design(trajectories, seed, names, ranges),
                        crossings=crossings)


def design_sweep(scenario, out, make_design, *, crossings: bool = False):
    """A design over one tree's free inputs (:func:`free_inputs` of ``scenario``) as a sweep
    into ``out``: ``make_design(names, ranges)``'s rows (``ranges``: the tree's,
    :func:`ranges_of`) as ``input.*`` axes, :func:`answer_under` (with ``crossings``,
    :func:`answer_and_crossings`) at each point."""
    scen = resolve_scenario(scenario)
    names = free_inputs(scen)
    X = make_design(names, ranges_of(scen, names))
    return SweepSpec(scen, Design.of([f"input.{n}" for n in names],
                                     [tuple(float(v) for v in row) for row in X]),
                     Path(out), ("analytic",), identify=False, analysis=ANALYSES[crossings])


def _morris(names, X, y, ranges: dict | None = None) -> dict:
    """SALib's Morris analysis of ``y`` on the design ``X``: per input its mu, mu_star,
    sigma and mu_star_conf (SALib's keys; the interval's half-width at CONF_LEVEL from
    RESAMPLES bootstrap resamples, seeded)."""
    # lazy: +242 ms at import otherwise (scipy, pandas, SALib, numpy, pyarrow),
    # which this module's other callers do not need
    from SALib.analyze import morris

    with warnings.catch_warnings():  # one trajectory: sigma is undefined (NaN), fine
        warnings.simplefilter("ignore", RuntimeWarning)
        res = morris.analyze(problem(names, ranges), X, y, num_levels=LEVELS,
                             num_resamples=RESAMPLES, conf_level=CONF_LEVEL, seed=SEED)
    return {n: {k: float(res[k][i]) for k in ("mu", "mu_star", "sigma", "mu_star_conf")}
            for i, n in enumerate(names)}


def deciding(indices: dict) -> tuple[list[str], bool]:
    """(the inputs that decide an output, whether one is separated) from its Morris
    ``indices`` (input -> {mu_star, mu_star_conf}): the input of the
    largest mu* alone when its interval (mu* -+ mu_star_conf) lies above every other's,
    else it and every input whose interval reaches into its; [] when nothing moves it."""
    ranked = sorted(indices, key=lambda n: -indices[n]["mu_star"])
    top = indices[ranked[0]] if ranked else None
    if top is None or not top["mu_star"] > 0:
        return [], False
    floor = top["mu_star"] - top["mu_star_conf"]
    tied = [n for n in ranked[1:]
            if indices[n]["mu_star"] + indices[n]["mu_star_conf"] >= floor]
    return [ranked[0], *tied], not tied


def _convergence(names, X, y, full: dict, ranges: dict | None = None) -> dict | None:
    """mu* from the design's first half of trajectories against all of them (N/2 vs N):
    the largest change as a share of the largest mu*, and whether the deciding inputs are
    the same; None with fewer than 4 trajectories."""
    per = len(names) + 1
    r = len(X) // per
    if r < 4:
        return None
    half = (r // 2) * per
    part = _morris(names, X[:half], y[:half], ranges)
    scale = max(v["mu_star"] for v in full.values()) or 1.0
    change = max(abs(part[n]["mu_star"] - full[n]["mu_star"]) for n in names) / scale
    return {"trajectories": [r // 2, r], "mu_star_half": {n: part[n]["mu_star"] for n in names},
            "max_change": change, "same_deciding": deciding(part)[0] == deciding(full)[0]}


def design_rows(table, X, names) -> tuple[list, list]:
    """The sweep ``table``'s row of each point of the design ``X`` (columns ``names``), None
    where it has none, and those that failed or are missing. A point's key is its inputs to
    12 digits: the design's floats come back from the table (parquet) exactly; the rounding
    guards a text round trip."""
    rows = {tuple(round(float(r[f"input.{k}"]), 12) for k in names): r
            for r in table.to_dict("records")}
    got = [rows.get(tuple(round(float(v), 12) for v in x)) for x in X]
    return got, [r for r in got if r is None or r.get("status") != OK]


def analyse(table, trajectories: int, seed: int = SEED, names=None, *,
            held: dict | None = None, ranges: dict | None = None) -> dict:
    """Per output of the sweep's ``table`` (the design of ``trajectories`` and ``seed``):
    its range over the design's evaluations (min and max over the stated
    input ranges; not a probability interval), the Morris indices of each input with SALib's
    keys (mu* in the output's units, its 95 % interval mu_star_conf), the inputs that decide
    it (:func:`deciding`), the measurements that would settle them and the N/2 convergence
    check. ``names``: the design's inputs (default all); ``held``: the measured ones, at
    their values; ``ranges``: the tree's (:func:`ranges_of`; default the registry's).
    Crossing durations enter as log10 s, 'never' as twice the longest
    duration scanned (a censored value: the ranking holds, the mu* of a crossing that
    leaves the range is a lower bound).

    A point that did not run is kept (compare.studies.study_points: its index, inputs and
    reason; ``failed``, ``failed_points``); the indices rest on the complete trajectories
    only (``trajectories_used`` of ``trajectories``: a trajectory with a failed point gives
    no exact elementary effect and is dropped whole, never imputed), the lowest and highest
    on every point that ran (``evaluations``); no indices when no trajectory is complete.
    A point that ran without an output's number (NaN) drops its trajectory for that output
    alone (its ``basis`` counts them as ``non_finite``; ``refused``: the outputs left with
    none)."""
    names = list(INPUTS) if names is None else list(names)
    X = design(trajectories, seed, names, ranges)
    got, _ = design_rows(table, X, names)
    failed = failed_points(names, X, got, OK)
    per = len(names) + 1
    kept = complete_groups(len(X) // per, per, failed)
    idx = rows_of(kept, per)
    ran = [r for r in got if r is not None and r.get("status") == OK]
    out = {"inputs": inputs_entry(names, ranges),
           "held": dict(held or {}), "trajectories": trajectories, "evaluations": len(ran),
           "conf_level": CONF_LEVEL, "num_resamples": RESAMPLES,
           "trajectories_used": len(kept), **failure_summary(failed, len(X)),
           "outputs": {}, "refused": {}}
    if not failed:
        del out["errors"]
    if not kept:
        return out
    for name in (o for o in OUTPUTS if o in ran[0]):
        y_all = _values(name, ran)
        y_all = y_all[np.isfinite(y_all)]
        y = _values(name, [got[i] for i in idx])
        whole = [g for j, g in enumerate(kept) if np.all(np.isfinite(y[j * per:(j + 1) * per]))]
        if not whole:  # a point that ran without this number: its trajectory gives none
            out["refused"][name] = (f"no complete trajectory has a finite {name} "
                                    f"({len(kept)} complete, each with a point without it)")
            continue
        sel = rows_of(whole, per)
        out["outputs"][name] = _output_entry(name, names, X[sel],
                                             _values(name, [got[i] for i in sel]), y_all,
                                             ranges, {"trajectories": len(whole),
                                                      "of": trajectories, "points": len(sel),
                                                      "non_finite": len(kept) - len(whole)})
    return out


def _output_entry(name: str, names, X, y, y_all, ranges, basis: dict) -> dict:
    """study.json's entry of the output ``name`` (:func:`analyse`): its lowest and highest
    over every point that ran (``y_all``), the Morris indices and N/2 check on the complete
    trajectories' points ``X`` and values ``y``, the deciding inputs and their ``basis``."""
    indices = _morris(names, X, y, ranges)
    decide, separated = deciding(indices)
    return {"low": float(np.min(y_all)), "high": float(np.max(y_all)),
            "evaluations": int(y_all.size), "basis": basis,
            "never": int(np.sum(y_all >= math.log10(2.0 * DURATIONS[-1]) - 1e-12))
            if name.startswith("crossing.") else 0,
            "indices": indices, "deciding": decide, "separated": separated,
            "settle": [ALL_INPUTS[n][4] for n in decide],
            "convergence": _convergence(names, X, y, indices, ranges)}


def _values(name: str, rows) -> np.ndarray:
    """One output's values on ``rows``: a crossing duration as log10 s, 'never' as twice
    the longest duration scanned (:func:`analyse`)."""
    y = np.array([float(r[name]) for r in rows])
    if name.startswith("crossing."):
        y = np.log10(np.where(np.isfinite(y), y, 2.0 * DURATIONS[-1]))
    return y
