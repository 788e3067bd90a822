"""The engines' stepping by phase against their fixed step (``bench_chains.py --phases``):
the convergence table and the steps and wall times, in one process.

Per case (every shipped tree's report chains and a tree unlike them, ``LIGHT``: a light
pendulum that rebounds): the run at a fixed step dt (the rule's step, given as ``--dt``:
what every run was before), at dt / 2 (that the fixed-step answer is converged) and stepped
by phase (the default, analytic.engine.phases). Each metric the engines are compared by
(compare/runs/tolerances.toml [engines.chain], [engines.pendulum] for the full pendulum: the same
model in two integrators) and the first contact's duration (read at the contact step's
resolution, so within one dt_c) is judged: |dt/2 - dt| and |phased - dt| relative to the
fixed-step value, each against the stated tolerance. The timing: ``rounds`` rounds, each
running the fixed-step and the phased run of every case one after the other (alternating
which goes first), the medians of their walls (the whole run, and the stepping alone) and
their ratio, with the steps of each.
"""

from __future__ import annotations

import statistics
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: The tree unlike the shipped ones: central-leader struck by a 20 kg pendulum at e = 0.5.
LIGHT = str(ROOT / "tests" / "data" / "light-pendulum.toml")
#: The tolerance table judging each pendulum's runs (the engines compared on one model).
SECTIONS = {"linear": "chain", "full": "pendulum"}
EXTRA = "first_contact_duration"  # judged within one contact step (its resolution)


def cases(report_cases, engines) -> list:
    """The report's chain cases of ``engines`` and the light pendulum's chain (linear) per
    engine, at central-leader's segments."""
    out = [c for c in report_cases if c[1] in engines]
    out += [(LIGHT, e, {"trunk": "chain", "segments": 12, "pendulum": "linear"})
            for e in engines]
    return out


def stated(entry: dict) -> float | None:
    """The relative tolerance a phased run is judged by against the fixed step, from one
    compare/runs/tolerances.toml entry: its ``rel``, or for a per-tree bound its ``floor`` (what
    stays at any step; the bound's first-order part, 2 |Delta(dt) - Delta(dt / 2)| of two
    integrators, is left out: the phased and fixed runs are one engine); None for an entry
    with neither (undefined, report only)."""
    if "rel" in entry:
        return float(entry["rel"])
    return float(entry["floor"]) if "bound" in entry and "floor" in entry else None


def tolerances(pendulum: str) -> dict:
    """metric -> stated relative tolerance (:func:`stated`) of [engines.chain] or
    [engines.pendulum] for the ``pendulum`` ("linear" or "full")."""
    from treeimpact.compare.runs.verdicts import TOLERANCES_PATH

    table = tomllib.loads(Path(TOLERANCES_PATH).read_text())["engines"][SECTIONS[pendulum]]
    out = {k: t for k, t in ((k, stated(v)) for k, v in table.items()) if t is not None}
    if not out:  # a changed file format must not leave the table judging nothing
        raise ValueError(f"no tolerance read from [engines.{SECTIONS[pendulum]}]")
    return out


def _run(engine, scen, opts, dt=None):
    """One run of ``scen`` on ``engine`` with ``opts`` and its wall time, s: at ``dt`` (s, a
    fixed step) or, with None, by phase (the engine's ``_setup.PHASED`` switched on, both
    engines' default, so that the phased side stays phased if a default changes)."""
    import importlib

    from treeimpact.compare.runs.backends import get_backend
    from treeimpact.compare.runs.cache import resolve_scenario

    importlib.import_module(f"treeimpact.{engine}_models._setup").PHASED = True
    t0 = time.perf_counter()
    r = get_backend(engine).simulate(resolve_scenario(scen), **opts,
                                     **({} if dt is None else {"dt": dt}))
    return r, time.perf_counter() - t0


def _rel(a: float, b: float) -> float:
    return float(abs(a - b) / abs(b) if b else abs(a))


def convergence(scen, engine, opts) -> dict:
    """The case's three runs and, per judged metric, the fixed step's convergence (dt/2 vs
    dt), the phased run's change (vs dt) and the tolerance, each relative."""
    phased, _ = _run(engine, scen, opts)
    dt = phased.model["dt"]
    fixed, _ = _run(engine, scen, opts, dt)
    half, _ = _run(engine, scen, opts, dt / 2)
    tol = tolerances(opts["pendulum"])
    tol[EXTRA] = dt / fixed.metrics[EXTRA]
    rows = {}
    for k, t in tol.items():
        f, h, p = fixed.metrics[k], half.metrics[k], phased.metrics[k]
        rows[k] = {"fixed": f, "half": h, "phased": p, "tolerance": t,
                   "converged": _rel(h, f), "phased_change": _rel(p, f),
                   "phased_vs_half": _rel(p, h),
                   "within": _rel(h, f) <= t and _rel(p, f) <= t}
    st = phased.extra["stepping"]
    return {"dt": dt, "free_dt": st["free_dt"], "metrics": rows,
            "all_within": all(r["within"] for r in rows.values()),
            "worst_share": max(r["phased_change"] / r["tolerance"] for r in rows.values()),
            "episodes": [fixed.metrics["contact_episodes"], phased.metrics["contact_episodes"]]}


def timing(case_list, dts, rounds: int) -> list:
    """Per case the fixed-step (at its ``dts`` entry, s) and phased runs' median walls (s:
    whole run, stepping), their ratios and steps, over ``rounds`` alternating rounds."""
    walls = {i: {"fixed": [], "phased": []} for i in range(len(case_list))}
    steps = {}
    for r in range(rounds):
        for i, (scen, engine, opts) in enumerate(case_list):
            dt = dts[i]
            order = ("fixed", "phased") if (r + i) % 2 == 0 else ("phased", "fixed")
            for side in order:
                res, wall = _run(engine, scen, opts, dt if side == "fixed" else None)
                st = res.extra["stepping"]
                walls[i][side].append((wall, st["stepping_s"]))
                steps.setdefault(i, {})[side] = st["steps"]
                steps[i]["free_" + side] = st.get("free_steps", 0)
    out = []
    for i, case in enumerate(case_list):
        med = {s: [statistics.median(w[j] for w in walls[i][s]) for j in (0, 1)]
               for s in ("fixed", "phased")}
        out.append({"case": list(case), "rounds": rounds,
                    "fixed_s": round(med["fixed"][0], 4), "phased_s": round(med["phased"][0], 4),
                    "ratio": round(med["phased"][0] / med["fixed"][0], 3),
                    "fixed_stepping_s": round(med["fixed"][1], 4),
                    "phased_stepping_s": round(med["phased"][1], 4),
                    "stepping_ratio": round(med["phased"][1] / med["fixed"][1], 3),
                    "fixed_steps": steps[i]["fixed"], "phased_steps": steps[i]["phased"],
                    "phased_free_steps": steps[i]["free_phased"],
                    "steps_ratio": round(steps[i]["phased"] / steps[i]["fixed"], 3)})
    return out


def name_of(case) -> str:
    scen, engine, opts = case
    return f"{Path(scen).stem}.{engine}.{opts['trunk']}.{opts['pendulum']}"


def measure(report_cases, engines, rounds: int) -> tuple[dict, dict]:
    """(flat numbers, details) of the convergence and the timing of every case."""
    case_list = cases(report_cases, engines)
    for e in engines:  # warm each engine (imports, first calls) before anything is timed
        _run(e, "open-center", {"trunk": "chain", "segments": 4, "t_end": 0.03})
    conv = [convergence(*c) for c in case_list]
    times = timing(case_list, [cv["dt"] for cv in conv], rounds)
    numbers = {}
    for c, cv, tm in zip(case_list, conv, times):
        n = name_of(c)
        numbers[f"{n}.fixed_steps"] = tm["fixed_steps"]
        numbers[f"{n}.phased_steps"] = tm["phased_steps"]
        numbers[f"{n}.ratio"] = tm["ratio"]
        numbers[f"{n}.stepping_ratio"] = tm["stepping_ratio"]
        numbers[f"{n}.worst_share"] = round(cv["worst_share"], 4)
        numbers[f"{n}.all_within"] = cv["all_within"]
    for e in engines:
        sel = [(cv, tm) for c, cv, tm in zip(case_list, conv, times) if c[1] == e]
        numbers[f"{e}.fixed_steps"] = [min(t["fixed_steps"] for _, t in sel),
                                       max(t["fixed_steps"] for _, t in sel)]
        numbers[f"{e}.phased_steps"] = [min(t["phased_steps"] for _, t in sel),
                                        max(t["phased_steps"] for _, t in sel)]
        numbers[f"{e}.ratio"] = [min(t["ratio"] for _, t in sel), max(t["ratio"] for _, t in sel)]
        numbers[f"{e}.stepping_ratio"] = [min(t["stepping_ratio"] for _, t in sel),
                                          max(t["stepping_ratio"] for _, t in sel)]
        numbers[f"{e}.worst_share"] = round(max(cv["worst_share"] for cv, _ in sel), 4)
    numbers["all_within"] = all(cv["all_within"] for cv in conv)
    details = {"rounds": rounds, "engines": list(engines),
               "cases": [{"case": list(c), "convergence": cv, "timing": tm}
                         for c, cv, tm in zip(case_list, conv, times)]}
    from treeimpact.analytic.results import to_jsonable

    return to_jsonable(numbers), to_jsonable(details)
