"""Variance-based sensitivity of the answer's gaps (Sobol indices, SALib) over the unmeasured
inputs of compare.studies.sensitivity, each uniform over its stated range (:data:`INPUTS`):
the Saltelli/Sobol design (``SALib.sample.sobol``, no second order), per output S1 and ST
with their bootstrap intervals (``SALib.analyze.sobol``), the same indices from the design's
first N/2 base samples (the convergence check), and the rule that words each output:

* inputs ranked by ST; the order of the first k is *settled* when each of them has its ST
  interval (ST -+ ST_conf) wholly above every lower-ranked input's and holds the same rank
  at N/2 (:func:`settled_prefix`);
* k >= 1: "decided by X" (", then Y" for each further settled input); k = 0: "unsettled",
  naming the tied set: the top input and every input whose interval reaches its lower end
  (:func:`verdict`); an output that no input moves (no spread over the design): "nothing".

What to measure first (:func:`measure_first`): the free inputs ranked by their largest ST
over the answered gaps, each with the measurement that fixes it, and per gap the verdict's
measurement. Design notes: docs/sensitivity.md. Indices are shares of variance (1).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from treeimpact.analytic.errors import ParameterError

from ..runs.cache import OK
from .sensitivity import ANSWER, CONF_LEVEL, design_rows, design_sweep
from .study_inputs import ALL_INPUTS, INPUTS, inputs_entry, problem
from .study_points import complete_groups, failed_points, failure_summary, rows_of

#: The seed of the scrambled Sobol sequence and of SALib's bootstrap.
SEED = 20261128
#: Bootstrap resamples of S1_conf and ST_conf (SALib's default 100 leaves the interval's own
#: sampling error near 10 %; 1000 brings it near 3 % for a negligible cost).
RESAMPLES = 1000
#: The gaps the first screen's "what to measure first" names a measurement for: the two
#: the answer's first sentence quotes.
HEADLINE = ("gap.x_max", "gap.energy_delivered")
INDEX_KEYS = ("S1", "S1_conf", "ST", "ST_conf")


def sobol_design(n: int, names=None, seed: int = SEED, spec: dict | None = None) -> np.ndarray:
    """The Saltelli design of ``n`` base samples (a power of two) over :data:`INPUTS` (only
    ``names``; or the SALib problem ``spec``), scrambled Sobol points of ``seed``:
    n x (inputs + 2) rows, each base sample's block (A, the inputs' AB rows, B) after the
    other, so its first n/2 blocks are the design of n/2. ParameterError naming ``sobol``
    unless n is a power of two (a Sobol sequence is balanced only at those)."""
    # lazy: +250 ms at import otherwise (scipy, pandas, SALib, numpy, pyarrow),
    # which this module's other callers do not need
    from SALib.sample import sobol


    if n < 1 or n & (n - 1):
        raise ParameterError(f"sobol: N = {n}, allowed a power of two (1, 2, 4, ... 4096)")
    return sobol.sample(spec or problem(names), n, calc_second_order=False, scramble=True,
                        seed=seed)


def sobol_indices(names, y, spec: dict | None = None) -> dict | None:
    """SALib's Sobol analysis of ``y`` on :func:`sobol_design` over ``names`` (or the SALib
    problem ``spec``, whose names ``names`` are): per input
    {S1, S1_conf, ST, ST_conf} (conf: the half-width of the CONF_LEVEL interval from
    RESAMPLES seeded bootstrap resamples); None when ``y`` has no spread (no variance to
    share)."""
    # lazy: +267 ms at import otherwise (scipy, pandas, SALib, numpy, pyarrow),
    # which this module's other callers do not need
    from SALib.analyze import sobol

    y = np.asarray(y, dtype=float)
    if not np.ptp(y) > 0:
        return None
    res = sobol.analyze(spec or problem(names), y, calc_second_order=False, num_resamples=RESAMPLES,
                        conf_level=CONF_LEVEL, seed=SEED)
    return {n: {k: float(res[k][i]) for k in INDEX_KEYS} for i, n in enumerate(names)}


def ranked(indices: dict) -> list[str]:
    """The inputs of ``indices`` by ST, largest first (ties by name, for a stable order; a
    non-finite ST last)."""
    return sorted(indices, key=lambda n: (-indices[n]["ST"] if math.isfinite(indices[n]["ST"])
                                          else math.inf, n))


def bounds(index: dict) -> tuple[float, float]:
    """An input's ST interval from its ``index`` (ST - ST_conf, ST + ST_conf); (-inf, inf)
    when either is not finite (a bootstrap with no spread to resample: nothing is known)."""
    st, conf = index["ST"], index["ST_conf"]
    if not (math.isfinite(st) and math.isfinite(conf)):
        return -math.inf, math.inf
    return st - conf, st + conf


def settled_prefix(full: dict, half: dict | None) -> int:
    """How many leading inputs' order is settled: the largest k such that each of the first
    k inputs by ST (``full``) has its interval (:func:`bounds`) wholly above every lower-
    ranked input's, and the same rank by ST at N/2 (``half``; None: no N/2 check, nothing
    settled)."""
    if half is None:
        return 0
    order, order_half = ranked(full), ranked(half)
    k = 0
    for i, name in enumerate(order[:-1]):
        low = bounds(full[name])[0]
        rest = max(bounds(full[n])[1] for n in order[i + 1:])
        if not (low > rest and order_half[i] == name):
            break
        k += 1
    if k == len(order) - 1 and order_half[-1] == order[-1]:
        k = len(order)  # the last one is settled when all above it are
    return k


def verdict(full: dict | None, half: dict | None) -> dict:
    """The stated rule (module docstring) on one output's indices at N (``full``) and N/2
    (``half``): {status: settled | unsettled | nothing, order (by ST), settled (the first
    inputs whose order is settled), tied (unsettled: the top input and those whose ST
    interval reaches its lower end; else [])}."""
    if full is None:
        return {"status": "nothing", "order": [], "settled": [], "tied": []}
    order = ranked(full)
    k = settled_prefix(full, half)
    if k:
        return {"status": "settled", "order": order, "settled": order[:k], "tied": []}
    floor = bounds(full[order[0]])[0]
    tied = [order[0]] + [n for n in order[1:] if bounds(full[n])[1] >= floor]
    return {"status": "unsettled", "order": order, "settled": [], "tied": tied}


def verdict_text(v: dict, label=str) -> str:
    """A :func:`verdict` ``v`` in words, inputs named by ``label``: 'decided by A, then B',
    'unsettled: A, B or C (ST intervals overlap)', 'unsettled: A ranks first at N but not at
    N/2', or 'no input moves it'."""
    if v["status"] == "nothing":
        return "no input moves it"
    if v["status"] == "settled":
        return "decided by " + ", then ".join(label(n) for n in v["settled"])
    tied = [label(n) for n in v["tied"]]
    if len(tied) == 1:
        return f"unsettled: {tied[0]} ranks first at N but not at N/2"
    return f"unsettled: {', '.join(tied[:-1])} or {tied[-1]} (ST intervals overlap)"


def convergence(names, y, n: int, spec: dict | None = None) -> tuple:
    """The indices (:func:`sobol_indices` over ``names`` or ``spec``) at N (the outputs
    ``y`` of the design of ``n`` base samples) and at N/2 (its first n/2 blocks); the N/2
    ones None below 4 base samples."""
    full = sobol_indices(names, y, spec)
    if n < 4 or full is None:
        return full, None
    rows = (n // 2) * (len(names) + 2)
    return full, sobol_indices(names, np.asarray(y)[:rows], spec)


def output_entry(names, y, n: int, spec: dict | None = None) -> dict:
    """One output's Sobol part (its values ``y`` on the design of ``n`` over ``names`` or
    ``spec``): the indices at N with each input's N/2 values and the change of ST and S1
    from N/2 to N beside them, the :func:`verdict` and the output's spread (min, max)."""
    full, half = convergence(names, y, n, spec)
    idx = {}
    for name in names:
        if full is None:
            break
        row = dict(full[name])
        if half is not None:
            row |= {"ST_half": half[name]["ST"], "S1_half": half[name]["S1"],
                    "ST_change": full[name]["ST"] - half[name]["ST"],
                    "S1_change": full[name]["S1"] - half[name]["S1"]}
        idx[name] = row
    return {"indices": idx, **verdict(full, half), "low": float(np.min(y)),
            "high": float(np.max(y))}


def analyse_sobol(table, n: int, names=None, seed: int = SEED,
                  ranges: dict | None = None) -> dict:
    """Per answered gap of the sweep's ``table`` (:func:`sobol_design` of ``n`` and ``seed``
    over ``names``, default every input, on the tree's ``ranges``,
    compare.studies.study_inputs.ranges_of; default the registry's): :func:`output_entry`;
    and :func:`measure_first`. {n, evaluations (points that ran), points, failed,
    failed_points, blocks_used, conf_level, num_resamples, distribution, inputs, outputs,
    measure_first} (errors: up to 5 distinct reasons when points failed).

    A failed point breaks its Saltelli block (A, the inputs' AB rows, B: each index's
    estimator reads all of them), so the indices and their bootstrap intervals are computed
    on the complete blocks only, ``blocks_used`` of n (each output's ``basis`` says so; its
    N/2 check on the first half of them), the failed points kept with their reasons
    (compare.studies.study_points), never imputed; no indices when no block is complete.
    The indices then describe the inputs' box less the failed blocks' points. A point that
    ran without a gap's number (NaN) drops its block for that gap alone (``basis``:
    ``non_finite``)."""
    names = list(INPUTS) if names is None else list(names)
    spec = problem(names, ranges) if ranges else None
    X = sobol_design(n, names, seed, spec)
    got, _ = design_rows(table, X, names)
    failed = failed_points(names, X, got, OK)
    size = len(names) + 2
    kept = complete_groups(n, size, failed)
    idx = rows_of(kept, size)
    out = {"n": n, "evaluations": len(X) - len(failed), "conf_level": CONF_LEVEL,
           "num_resamples": RESAMPLES, "seed": seed, "names": names,
           "distribution": "uniform over each input's stated range, independent",
           "inputs": inputs_entry(names, ranges), "blocks_used": len(kept),
           **failure_summary(failed, len(X)), "outputs": {}}
    if not failed:
        del out["errors"]
    if not kept:
        return out
    rows = [got[i] for i in idx]
    for key in (f"gap.{m}" for m in ANSWER if f"gap.{m}" in rows[0]):
        y = np.array([float(r[key]) for r in rows])
        whole = [g for j, g in enumerate(kept) if np.all(np.isfinite(y[j * size:(j + 1) * size]))]
        if not whole:  # every complete block has a point without this number
            out["outputs"][key] = {"status": "nothing", "error": "non-finite values"}
            continue
        sel = rows_of(whole, size)
        y = np.array([float(got[i][key]) for i in sel])
        with warnings.catch_warnings():  # a constant block of the bootstrap: nan conf, said
            warnings.simplefilter("ignore", RuntimeWarning)
            out["outputs"][key] = output_entry(names, y, len(whole), spec) | {
                "basis": {"blocks": len(whole), "of": n, "points": len(sel),
                          "non_finite": len(kept) - len(whole)}}
    out["measure_first"] = measure_first(out["outputs"])
    return out


def measure_first(outputs: dict) -> dict:
    """What to measure first from the gaps' Sobol entries ``outputs`` (:func:`output_entry`):
    rows, one per input ranked by its largest ST over the gaps (input, the measurement that
    fixes it, per gap its ST, ST_conf and rank), and per headline gap (:data:`HEADLINE`) the
    verdict's measurement: {gap: {status, inputs, measurements}}."""
    gaps = {k: v for k, v in outputs.items() if v.get("indices")}
    names = list(dict.fromkeys(n for v in gaps.values() for n in v["indices"]))
    rows = []
    for name in names:
        shares = {k: {"ST": v["indices"][name]["ST"], "ST_conf": v["indices"][name]["ST_conf"],
                      "rank": v["order"].index(name) + 1} for k, v in gaps.items()}
        rows.append({"input": name, "measurement": ALL_INPUTS[name][4], "gaps": shares,
                     "largest_ST": max((s["ST"] for s in shares.values()
                                        if math.isfinite(s["ST"])), default=math.nan)})
    rows.sort(key=lambda r: (-r["largest_ST"] if math.isfinite(r["largest_ST"]) else math.inf,
                             r["input"]))
    first = {}
    for key in HEADLINE:
        v = outputs.get(key)
        if v is None:
            continue
        chosen = v.get("settled", [])[:1] or v.get("tied", [])
        first[key] = {"status": v.get("status", "nothing"), "inputs": chosen,
                      "measurements": [ALL_INPUTS[n][4] for n in chosen]}
    return {"rows": rows, "first": first}


def sobol_sweep(scenario, out, n: int, seed: int = SEED):
    """The Sobol study of one tree (``scenario``) as a sweep into ``out``: the design of
    :func:`sobol_design` (``n``, ``seed``) over its free inputs on the tree's ranges
    (compare.studies.study_inputs.ranges_of) as ``input.*`` axes, the answer's gaps
    (compare.studies.sensitivity.answer_under) at each point."""
    return design_sweep(scenario, out, lambda names, ranges: sobol_design(
        n, names, seed, problem(names, ranges)))
