"""The small-e answer: for each consequence the paper draws from "e is small", the largest
restitution e up to which it stays within the validity tolerance of the exact result, and
its error at the tree's own e; beside them the 1-DOF assumption's gaps as functions of e,
so that a reader sees whether e or the trunk decides.

Each tree runs as one sweep over :data:`E_GRID` (the exact 1-DOF solver's run at each e,
the analysis :func:`errors_at_run` adding the paper's procedure on its record and the
continuum trunk with the same pad); :func:`small_e_answer` reads the table and locates each
first crossing of the tolerance by bisection to :data:`RESOLUTION`. Design notes and what
each curve is checked against: docs/report.md ("The small-e curves"). SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

from treeimpact.analytic.continuum.beam_impact import simulate_beam
from treeimpact.analytic.impact.simulate import simulate

from ..runs.cache import OK, resolve_scenario
from ..runs.rungs import analytic_samples
from ..runs.verdicts import validity_tolerance
from ..tree.identification import IDENT_METRICS, identify_rung
from .small_e_curves import (  # noqa: F401 (the curves' reading, re-exported)
    MONOTONE_SLACK,
    RESOLUTION,
    bracket_text,
    first_crossing,
    monotone_until,
    steady_bracket,
    steady_text,
    verdict,
)
from .sweep.grid import Grid, value_axis
from .sweep.run import SweepSpec

#: The e of the curves (1): [0, 0.05] in steps of 0.005 (the identification's and eq 45's
#: crossings lie there), then to 0.9 in steps of 0.05.
E_GRID = tuple(round(0.005 * i, 3) for i in range(10)) + tuple(
    round(0.05 * i, 2) for i in range(1, 19))
#: Where an approximation has no value at e = 0 (eq 45: x0 = T0 = A_x = 0; the pad law needs
#: e > 0), its e = 0 point is read here (1).
E_FLOOR = 1e-3


@dataclass(frozen=True)
class Approximation:
    """One consequence of "e is small" (or of the 1-DOF trunk, as a function of e):
    ``label`` for tables, ``what`` it is compared with, the ``model`` its error needs
    ("exact": the exact 1-DOF solver; "continuum": the beam too)."""

    label: str
    what: str
    model: str = "exact"


#: The approximations, in the table's order. Errors: (approximation - exact) / |exact|;
#: the 1-DOF gaps as the answer table reads them, (continuum - 1-DOF) / |1-DOF|.
APPROXIMATIONS = {
    "eq57_energy_loss": Approximation(
        "eq 57 energy loss", "eq 57, the one-impact loss M_T m u1^2 / (2 (M_T + m)), against "
        "the exact loss over every impact (eq 56, the exact solver's sum over the event)"),
    "eq58_energy_transferred": Approximation(
        "eq 58 energy transferred (eq 57 restated)", "eq 58, the pendulum's loss (release "
        "to the exact model's rebound) less eq 57's, against the energy the exact model "
        "delivers: with the exact rebound its error is eq 57's times the loss over the "
        "energy delivered, so it restates eq 57, not an independent check"),
    "identification_M_T": Approximation(
        "identified M_T (eq 44)", "the paper's procedure (eqs 39-47) on the exact 1-DOF "
        "model's own record, against its M_T"),
    "identification_K_T": Approximation(
        "identified K_T (eq 46)", "the paper's procedure on the exact record, against its "
        "K_T"),
    "identification_pair_damping_ratio": Approximation(
        "identified xi (eqs 42-43)", "the paper's procedure on the exact record, against "
        "the moving-together pair's damping ratio"),
    "eq45_area": Approximation(
        "eq 45 area A_x", "eq 45 as Table 1 reads it, x0 T0 / 2, against the exact A_x "
        "(the integral of x over the impact process)"),
    "one_dof_x_max": Approximation(
        "1-DOF trunk: x_max", "the continuum trunk's x_max against the 1-DOF model's (the "
        "same pad at each e)", "continuum"),
    "one_dof_energy_delivered": Approximation(
        "1-DOF trunk: energy delivered", "the continuum trunk's energy delivered against "
        "the 1-DOF model's (the same pad at each e)", "continuum"),
}
#: The sweep table's columns: each approximation's error, and why it has none.
COLUMNS = tuple(f"small_e.{n}" for n in APPROXIMATIONS) + tuple(
    f"small_e_reason.{n}" for n in APPROXIMATIONS)


def at_restitution(scenario, e: float):
    """``scenario`` with restitution ``e`` (1)."""
    return replace(scenario, contact=replace(scenario.contact, restitution=float(e)))


def _rel(approx: float, exact: float) -> float:
    ok = math.isfinite(approx) and math.isfinite(exact) and exact != 0.0
    return (approx - exact) / abs(exact) if ok else math.nan


def energy_errors(result) -> dict:
    """eqs 57 and 58 against the exact run ``result`` (the analytic backend's, at its own
    e): relative errors, NaN where the bodies have not parted for good within t_end (no
    rebound, no final loss to compare with)."""
    sol, m = result.solution, result.metrics
    model = sol.model
    eq57 = model.reduced_mass * model.impact_speed ** 2 / 2.0  # J
    exact_loss = m["contact_dissipation"]  # J, eq 55 summed over every impact and tail
    eq58 = model.initial_energy - m["rebound_energy"] - eq57  # J: m g l_e (cos th_b - cos th_r)
    return {"eq57_energy_loss": _rel(eq57, exact_loss),
            "eq58_energy_transferred": _rel(eq58, m["energy_delivered"])}


def area_error(result) -> float:
    """eq 45 as Table 1 reads it, x0 T0 / 2 (m s), against the exact A_x of ``result``
    (NaN where the bodies never move together: no impact process to integrate)."""
    m = result.metrics
    return _rel(0.5 * m["x0"] * m["T0"], m["A_x"])


def exact_run(scenario, e: float):
    """(the exact 1-DOF solver's run at ``e`` with the record the paper's procedure reads,
    the scenario at ``e``)."""
    s = at_restitution(scenario, e)
    return simulate(s, samples=analytic_samples(s.t_end)), s


def continuum_gaps(scenario, e: float, newton=None) -> dict:
    """The 1-DOF assumption of ``scenario`` at ``e`` (read at :data:`E_FLOOR` below it): the
    continuum trunk's gap to the 1-DOF model on x_max and the energy delivered, the same pad;
    ``newton``: the exact run's metrics at ``e`` when already made."""
    s = at_restitution(scenario, max(e, E_FLOOR))
    if newton is None or e < E_FLOOR:
        newton = simulate(s, samples=2).metrics
    beam = simulate_beam(s).metrics
    return {f"one_dof_{k}": _rel(beam[k], newton[k]) for k in ("x_max", "energy_delivered")}


def _why_none(name: str) -> str:
    if name == "eq45_area":
        return "the bodies never move together (no impact process to integrate)"
    if name.startswith("eq5"):
        return "the bodies do not part for good within t_end"
    return "no value"


def second_strike(result) -> bool:
    """Whether the exact run ``result`` strikes again after the bodies parted: an impact
    after the first separation, or more than one impact and the bodies never together (the
    energy curves then count that strike in their loss)."""
    sol = result.solution
    if sol.separations and any(i.t > sol.separations[0].t for i in sol.impacts):
        return True
    return not sol.together_starts and len(sol.impacts) > 1


def first_contact_error(scenario, e: float) -> float:
    """eq 57 against the loss of the first contact only of the exact run of ``scenario`` at
    ``e`` (relative): its impacts up to the first separation where the bodies move
    together, else the first impact alone ((1 - e^2) of eq 57's loss, so the error is
    e^2 / (1 - e^2)): the curve without the second strike :func:`second_strike` flags."""
    sol = exact_run(scenario, e)[0].solution
    model, impacts = sol.model, sol.impacts
    if sol.together_starts:
        end = sol.separations[0].t if sol.separations else math.inf
        loss = sum(i.loss for i in impacts if i.t < end)
    else:
        loss = impacts[0].loss
    return _rel(model.reduced_mass * model.impact_speed ** 2 / 2.0, loss)


def errors_of_run(result, scenario, *, continuum: bool = True) -> dict:
    """The sweep table's columns at the exact run ``result`` (at the scenario's own e, with
    the record the procedure needs): each approximation's error (``small_e.NAME``) and why
    it has none (``small_e_reason.NAME``); the paper's procedure's values as the
    identification sweep's ``id.*``, ``truth.*``, ``id_error`` and ``T0`` columns (the
    scenario section's table of the identification against e); the continuum's gaps only
    with ``continuum``."""
    e = scenario.contact.restitution
    errors = energy_errors(result)
    floor = result if e >= E_FLOOR else exact_run(scenario, E_FLOOR)[0]
    errors["eq45_area"] = area_error(floor)
    ident = identify_rung(result, scenario)
    out = {"T0": result.metrics["T0"], "id_error": None if ident.ok else ident.reason,
           "second_strike": second_strike(result)}
    out |= {f"truth.{k}": v for k, v in ident.truth.items()}
    out |= {f"id.{k}": ident.values.get(k, math.nan) for k in IDENT_METRICS}
    errors |= {f"identification_{k}": ident.errors.get(k, math.nan)
               for k in ("M_T", "K_T", "pair_damping_ratio")}
    if continuum:
        errors |= continuum_gaps(scenario, e, result.metrics)
    for name, approx in APPROXIMATIONS.items():
        if approx.model == "continuum" and not continuum:
            continue
        v = errors.get(name, math.nan)
        out[f"small_e.{name}"] = v
        reason = None
        if not math.isfinite(v):
            reason = ident.reason if name.startswith("identification_") else _why_none(name)
        out[f"small_e_reason.{name}"] = reason
    return out


def errors_at_run(result, scenario, record=None) -> dict:
    """The sweep's analysis (compare.studies.sweep.run): :func:`errors_of_run` of ``result`` (a run
    of ``scenario``) with the continuum; ``record`` (the sweep's) is not read."""
    return errors_of_run(result, scenario)


errors_at_run.columns = COLUMNS + ("T0", "id_error", "second_strike") + tuple(
    f"{p}.{k}" for p in ("id", "truth") for k in ("M_T", "K_T", "pair_damping_ratio", "E"))


def grid_of(scenario, grid=E_GRID) -> tuple:
    """``grid`` (default :data:`E_GRID`) with the scenario's own e (1)."""
    return tuple(sorted(set(grid) | {float(scenario.contact.restitution)}))


def small_e_sweep(scenario, out):
    """The small-e curves of one tree (``scenario``) as a sweep
    (:class:`compare.studies.sweep.run.SweepSpec`)
    into ``out``: the exact solver at every e of :func:`grid_of`, :func:`errors_at_run` on
    each."""
    scen = resolve_scenario(scenario)
    return SweepSpec(scen, Grid((value_axis("restitution", grid_of(scen)),)),
                     Path(out), ("analytic",), identify=True,
                     analysis="treeimpact.compare.studies.small_e:errors_at_run")


def small_e_table(scenario, grid=E_GRID):
    """The table :func:`small_e_sweep` writes, computed in this process (no sweep
    directory): one row per e of :func:`grid_of` ``scenario`` and ``grid`` (a pandas
    DataFrame)."""
    # lazy: +200 ms at import otherwise (pandas, numpy, pyarrow),
    # which this module's other callers do not need
    import pandas as pd


    scen = resolve_scenario(scenario)
    rows = []
    for e in grid_of(scen, grid):
        run, s = exact_run(scen, e)
        rows.append({"restitution": e, "status": OK, "error": None} | errors_at_run(run, s))
    return pd.DataFrame(rows)


class _Exact:
    """The exact runs a crossing's bisection asks for beyond the sweep's grid, each made
    once: ``at(name)(e)`` is approximation ``name``'s error at e (the continuum too for
    the 1-DOF gaps); ``seen(name)`` the (e, error) pairs computed so far."""

    def __init__(self, scenario):
        self.scenario, self.cache = scenario, {}

    def at(self, name):
        model = APPROXIMATIONS[name].model

        def error(e):
            key = (e, model)
            if key not in self.cache:
                run, s = exact_run(self.scenario, e)
                self.cache[key] = errors_of_run(run, s, continuum=model == "continuum")
            return self.cache[key][f"small_e.{name}"]
        return error

    def seen(self, name) -> list:
        model = APPROXIMATIONS[name].model
        return [(e, c[f"small_e.{name}"]) for (e, mdl), c in self.cache.items()
                if mdl == model and f"small_e.{name}" in c]


def small_e_answer(scenario, table, tolerance: float | None = None) -> dict:
    """The small-e answer of one tree (``scenario``) from its sweep's ``table``
    (:func:`small_e_sweep`), judged against ``tolerance`` (None: the studies' validity
    tolerance):
    per approximation {holds_up_to_e, bracket, error_at_e, e, e_grid, errors, reasons,
    error_at_zero, verdict, label, what}; errors relative (NaN where none, with its
    reason), e in 1. The crossings are bisected here (the exact solver, and the continuum
    for the 1-DOF gaps, at a few more e)."""
    tol = validity_tolerance() if tolerance is None else tolerance
    rows = sorted(table.to_dict("records"), key=lambda r: float(r["restitution"]))
    exact, split = _Exact(scenario), k_t_split(scenario)
    out = {}
    for name in APPROXIMATIONS:
        out[name] = _curve(name, rows, scenario, exact, tol)
        _extras(out[name], name, rows, scenario, exact, tol, split)
    return out


def _curve(name: str, rows: list, scenario, exact: _Exact, tol: float) -> dict:
    """Approximation ``name``'s curve over the sweep's ``rows``: its crossing of ``tol``
    bisected with ``exact``, monotonicity before it, a counted second strike, its error at
    the tree's own e, the reasons for missing points, and the verdict."""
    approx, e0 = APPROXIMATIONS[name], float(scenario.contact.restitution)
    grid = [float(r["restitution"]) for r in rows]
    values = [_float(r.get(f"small_e.{name}")) if r.get("status") == OK else math.nan
              for r in rows]
    holds, bracket = first_crossing(grid, values, exact.at(name), tol)
    mono = monotone_until(sorted([*zip(grid, values), *exact.seen(name)]),
                          bracket[1]) if bracket else True
    strikes = [e for e, r in zip(grid, rows) if r.get("second_strike") in (True, 1, "True")]
    strike_from = min(strikes) if strikes and approx.model == "exact" \
        and name.startswith("eq5") else None
    if strike_from is not None and strike_from > (bracket[1] if bracket else holds):
        strike_from = None
    at_e = next((v for e, v in zip(grid, values) if abs(e - e0) < 1e-12), None)
    reasons = {f"{e:g}": str(r.get(f"small_e_reason.{name}") or r.get("error"))
               for e, v, r in zip(grid, values, rows) if not math.isfinite(v)}
    return {"label": approx.label, "what": approx.what, "model": approx.model, "e": e0,
            "holds_up_to_e": holds, "bracket": list(bracket) if bracket else None,
            "error_at_e": at_e, "error_at_zero": values[0], "e_grid": grid,
            "errors": values, "reasons": reasons, "monotone": mono,
            "second_strike_from": strike_from,
            "verdict": verdict(holds, bracket, values[0], grid, tol, mono, strike_from)}


def _extras(a: dict, name: str, rows: list, scenario, exact: _Exact, tol: float,
            split: dict) -> None:
    """Add to curve ``a`` of ``name``: eq 57's first-contact crossing when it counts a
    second strike, a 1-DOF gap's steady bracket (:func:`steady_bracket`), K_T's e = 0
    ``split``; each said in its verdict."""
    grid, values = a["e_grid"], a["errors"]
    if a["second_strike_from"] is not None and name == "eq57_energy_loss":
        first = [first_contact_error(scenario, e) for e in grid]
        a["first_contact_bracket"] = first_crossing(
            grid, first, lambda e: first_contact_error(scenario, e), tol)[1]
        if a["first_contact_bracket"] is not None:
            a["verdict"] += (" (the first contact only: "
                             f"{bracket_text(a['first_contact_bracket'])})")
    if a["model"] == "continuum" and a["holds_up_to_e"] == 0.0 and a["bracket"] is None:
        steady = steady_bracket(grid, values, exact.at(name), tol)
        a["steady_up_to_e"] = steady[0]
        a["steady_bracket"] = list(steady[1]) if steady[1] else None
        a["verdict"] += f"; {steady_text(steady, tol)}"
    if name == "identification_K_T":
        a["split_at_zero"] = split
        a["verdict"] += (f" (the 10 ms fit {100 * split['fit']:+.0f} %, eq 46's "
                         f"damped frequency {100 * split['reading']:+.0f} %)")


def k_t_split(scenario) -> dict:
    """K_T's error at e = 0 of the tree ``scenario`` (one impact: the procedure's reading of
    the sequence plays no part) split into its two causes, relative to the true K_T: ``fit``, eq 46 read with
    the undamped omega_n (K_T = omega_n^2 (M_T + m) - k, exact for eq 34) on the 10 ms
    quadratic fit's omega_n and M_T: the fit's bias alone; ``reading``, eq 46 with the
    damped frequency omega_n sqrt(1 - xi^2) (the reading that reproduces Table 1) on the
    true omega_n, xi and M_T: the reading alone, -xi^2 omega_n^2 (M_T + m) / K_T;
    ``total``, the paper's reading on the fit (the curve's e = 0 point). NaN where the
    procedure refuses the record."""
    run, s = exact_run(scenario, 0.0)
    ident = identify_rung(run, s)
    truth = ident.truth
    if not ident.ok:
        return dict.fromkeys(("fit", "reading", "total"), math.nan)
    got, k_true = ident.identified, truth["K_T"]
    model = run.solution.model
    m, k = model.impactor_mass, model.impactor_stiffness
    wn_true = math.sqrt((k_true + k) / (truth["M_T"] + m))
    xi_true = truth["pair_damping_ratio"]
    fit = got["omega_n"] ** 2 * (got["M_T"] + m) - k
    reading = wn_true ** 2 * (1.0 - xi_true ** 2) * (truth["M_T"] + m) - k
    return {"fit": _rel(fit, k_true), "reading": _rel(reading, k_true),
            "total": ident.errors["K_T"]}


def _float(v) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan
