"""Validation of the identification as a study: synthetic pendulum-test records from the
analytic, soft and beam rungs over e x crown ratio, sampled as a test would be (rate, noise),
identified by the full-record fit (analytic.identify.record_fit) and by the paper's procedure
(analytic.identify.procedure, "paper" reading); errors against the SDOF truth, drawn as maps.
See docs/identification.md. SI units.

This module runs the study (its grid, its sweeps, their summaries); the cases and their
identification are :mod:`.ident_records`, the maps :mod:`.ident_maps`, the report's own
record fits :mod:`.ident_fits`."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from treeimpact.analytic.results import json_text
from treeimpact.compare.studies.sweep.run import SweepSpec, run_sweeps

from .ident_maps import identification_error_map
from .ident_records import ANALYSIS, NOISE, PARAMETERS, RATE, case_row

#: The grid: restitution and crown ratio (m_f / m_trunk), rungs whose records are identified.
RESTITUTIONS = (0.05, 0.1, 0.3, 0.5)
CROWN_RATIOS = (0.0, 1.0, 2.0, 4.0)
RUNGS = ("analytic", "soft", "beam")
METHODS = ("fit", "paper")
#: The issue's goal for the fit on SDOF records: within 2 % of the truth for e <= 0.3.
GOAL, GOAL_MAX_E = 0.02, 0.3
#: How the sampling matters: records (e = 0.1, no crown) at these rates (Hz) and noise levels
#: (fraction of the peak), a few seeds each (the full preset's; the default study takes the
#: first), of SAMPLING_RUNGS (the default study: exact SDOF records; every rung in the full
#: preset).
SAMPLING_RATES = (1e3, 5e3, 2e4)
SAMPLING_NOISES = (0.005, 0.01, 0.02)
SAMPLING_SEEDS = (1, 2)
SAMPLING_E = 0.1
SAMPLING_RUNGS = ("analytic",)
#: Engine hinged-chain records too, on a corner of the grid (a chain run costs 0.5-2.5 s), in
#: the summary table, not on the maps; ENGINE_RUNGS in the default study.
ENGINE_RUNGS = ("mujoco",)
ENGINE_RESTITUTIONS = (0.1, 0.3)
ENGINE_CROWN_RATIOS = (0.0, 4.0)


def _axis(name: str, values) -> str:
    return f"{name}=" + ",".join(str(v) for v in values)


def study_sweeps(out, scenario: str = "central-leader", *, restitutions=RESTITUTIONS,
                 crown_ratios=CROWN_RATIOS, rungs=RUNGS, sampling_rungs=SAMPLING_RUNGS,
                 engine_rungs=ENGINE_RUNGS, sampling_seeds=SAMPLING_SEEDS) -> dict:
    """The study as sweeps (name -> :class:`compare.studies.sweep.run.SweepSpec`) of the shipped
    ``scenario`` (its name or a TOML path) into ``out/identification/``: the grid of
    ``restitutions`` e (1) x ``crown_ratios`` (m_f / m_trunk, 1) on ``rungs``, the engines'
    corner (:data:`ENGINE_RESTITUTIONS` x :data:`ENGINE_CROWN_RATIOS`) on ``engine_rungs``,
    and the sampling grid (rate x noise x ``sampling_seeds`` on ``sampling_rungs``' records);
    an empty tuple leaves its sweep out. Each runs
    :func:`.ident_records.record_identification` on its records."""
    base = Path(out) / "identification"
    specs = {}
    if rungs:
        specs["grid"] = SweepSpec(scenario, [_axis("restitution", restitutions),
                                             _axis("crown_ratio", crown_ratios)],
                                  base / "grid", tuple(rungs), identify=False,
                                  analysis=ANALYSIS)
    if engine_rungs:
        specs["engines"] = SweepSpec(
            scenario, [_axis("restitution", ENGINE_RESTITUTIONS),
                       _axis("crown_ratio", ENGINE_CROWN_RATIOS)], base / "engines",
            tuple(engine_rungs), identify=False, analysis=ANALYSIS)
    if sampling_rungs:
        specs["sampling"] = SweepSpec(
            scenario, [_axis("restitution", (SAMPLING_E,)), _axis("crown_ratio", (0.0,)),
                       _axis("record.rate", SAMPLING_RATES),
                       _axis("record.noise", SAMPLING_NOISES),
                       _axis("record.seed", sampling_seeds)], base / "sampling",
            tuple(sampling_rungs), identify=False, analysis=ANALYSIS)
    return specs


def run_identification_study(out, scenario: str = "central-leader", *, workers=None,
                             restitutions=RESTITUTIONS, crown_ratios=CROWN_RATIOS,
                             rungs=RUNGS, sampling_rungs=SAMPLING_RUNGS,
                             engine_rungs=ENGINE_RUNGS, sampling_seeds=SAMPLING_SEEDS,
                             progress=None) -> dict:
    """Run (or resume) the study's sweeps (:func:`study_sweeps`, one pool of ``workers``
    processes: None one per core, 0 in this process); write ident-study.json and one map per
    method into ``out``; returns {rows, figures, summary, sampling}. ``scenario``,
    ``restitutions``, ``crown_ratios``, ``rungs``, ``sampling_rungs``, ``engine_rungs`` and
    ``sampling_seeds`` as :func:`study_sweeps` takes them. ``progress``: as the sweeps'
    (None: a bar on a terminal, nothing elsewhere; False: nothing)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    specs = study_sweeps(out, scenario, restitutions=restitutions, crown_ratios=crown_ratios,
                         rungs=rungs, sampling_rungs=sampling_rungs, engine_rungs=engine_rungs,
                         sampling_seeds=sampling_seeds)
    results = dict(zip(specs, run_sweeps(list(specs.values()), workers=workers,
                                         progress=progress)))
    wanted = {"grid": set(rungs), "engines": set(engine_rungs),
              "sampling": set(sampling_rungs)}
    rows = {name: [case_row(r) for r in res.table.to_dict("records")
                   if r["target"] in wanted[name]] for name, res in results.items()}
    grid = rows.get("grid", []) + rows.get("engines", [])
    summary = summarise(grid)
    mapped = [r for r in grid if r["rung"] in RUNGS]
    figures = [identification_error_map(mapped, method, out / f"ident-{method}.png")
               for method in METHODS] if mapped else []
    sampling_summary = summarise_sampling(rows["sampling"]) if rows.get("sampling") else []
    (out / "ident-study.json").write_text(json_text(
        {"scenario": scenario, "rate_hz": RATE, "noise": NOISE,
         "sweeps": {name: str(res.out.relative_to(out)) for name, res in results.items()},
         "summary": summary, "sampling": sampling_summary}, indent=1))
    return {"rows": grid + rows.get("sampling", []), "figures": figures, "summary": summary,
            "sampling": sampling_summary}


def summarise(rows: list[dict]) -> dict:
    """Per rung and method, over ``rows`` (the grid's cases as :func:`.ident_records.case_row`
    gives them): worst |error| (1, relative) per parameter over the grid and the share of
    e <= GOAL_MAX_E cells within GOAL, over the cells whose record fixes M_T and e; for the
    fit also how many records do not (one impact: ranges) and its worst error there with
    e given and with the pendulum's record, the share of intervals covering the truth and
    of records it explains. Returns {rung: {method: {...}}}."""
    out = {}
    for rung in dict.fromkeys(r["rung"] for r in rows):
        rr = [r for r in rows if r["rung"] == rung]
        entry = {}
        for method in METHODS:
            got = [r[method] for r in rr if method in r]
            small_e = [r for r in rr if r["restitution"] <= GOAL_MAX_E
                       and not r.get(f"{method}_not_fixed")]
            entry[method] = {  # a parameter the record does not fix (no error) is not
                # within the goal, and has no worst
                "identified": len(got), "cases": len(rr),
                "within_goal": float(np.mean([method in r and all(
                    abs(r[method].get(k, math.nan)) <= GOAL for k in PARAMETERS)
                    for r in small_e])) if small_e else math.nan,
                "worst": {k: max((abs(g[k]) for g in got if k in g), default=math.nan)
                          for k in PARAMETERS}}
        known = [r["fit_known_e"] for r in rr if "fit_known_e" in r]
        entry["fit"]["not_fixed"] = len(known)
        entry["fit"]["known_e_worst"] = max((abs(v) for k in known for v in k.values()),
                                            default=math.nan)
        entry["fit"]["with_y_worst"] = max((abs(v) for r in rr if "fit_with_y" in r
                                            for v in r["fit_with_y"].values()),
                                           default=math.nan)
        cov = [v for r in rr if "fit_covered" in r for v in r["fit_covered"].values()]
        entry["fit"]["covered"] = float(np.mean(cov)) if cov else math.nan
        expl = [r["explained"] for r in rr if "explained" in r]
        entry["fit"]["explained"] = float(np.mean(expl)) if expl else math.nan
        out[rung] = entry
    return out


def summarise_sampling(rows: list[dict]) -> list[dict]:
    """Per (rung, rate (Hz), noise) over the seeds of ``rows`` (the sampling sweep's cases
    as :func:`.ident_records.case_row` gives them): the fit's worst |error| (1, relative)
    over M_T, K_T and b, the share of its 95 % intervals covering the truth (M_T, K_T, C_T)
    and of records it says the 1-DOF model explains; one dict per cell, in the rows'
    order."""
    out = []
    for cell in dict.fromkeys((r.get("rung"), r["rate"], r["noise"]) for r in rows):
        rr = [r for r in rows if (r.get("rung"), r["rate"], r["noise"]) == cell]
        fits = [r["fit"] for r in rr if "fit" in r]
        cov = [v for r in rr if "fit_covered" in r for v in r["fit_covered"].values()]
        expl = [r["explained"] for r in rr if "explained" in r]
        out.append({"rung": cell[0], "rate_hz": cell[1], "noise": cell[2], "trials": len(rr),
                    "fitted": len(fits),
                    "worst": max((abs(v) for f in fits for v in f.values()), default=math.nan),
                    "covered": float(np.mean(cov)) if cov else math.nan,
                    "explained": float(np.mean(expl)) if expl else math.nan})
    return out
