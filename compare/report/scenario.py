"""Report section: one scenario's ladder, with the paper's Figs 4-5 redrawn for every rung,
the contact force, the impact sequence, the energy ledger, the ladder table and the
identification against the truth (including its dependence on e)."""

from __future__ import annotations

import math

import numpy as np

from treeimpact.analytic.model.plausible import implausible
from treeimpact.analytic.model.two_body import two_body_model
from treeimpact.analytic.results import to_jsonable

from ..runs.cache import OK, SKIPPED
from ..runs.rungs import RungKind
from ..runs.verdicts import Verdict
from ..studies.ident_fits import fit_one, fit_tasks
from ..tree.identification import IDENT_METRICS
from ..tree.ladder import ALL_METRICS, build_ladder, meaning_of, unit_of
from ..tree.mechanism import matched_loss_evidence
from . import figures, summary_figures
from .base import Section, tidy


def energy_ledger(rr) -> dict | None:
    """Energy terms at T0 (J) of one rung's result ``rr``: kinetic, potential (springs,
    gravity and the
    contact spring), damping work, impact loss, and eq 58's energy transferred. The first
    four sum to the initial energy; the residual is reported."""
    if not rr.ok:
        return None
    res = rr.result
    T0 = rr.values.get("T0", math.nan)
    if not math.isfinite(T0):
        return None
    if res.solution is not None:
        sol = res.solution
        terms = sol.energy_terms(T0)
        e0 = sol.model.initial_energy
        out = {"kinetic": terms["kinetic"], "potential": terms["potential"],
               "damping": terms["damping"], "impact loss": terms["impact_loss"]}
    elif res.record is not None:
        rec = res.record
        e0 = float(rec.kinetic[0] + rec.potential[0] + rec.damping_work[0] + rec.contact_work[0])

        def at(a):
            return float(np.interp(T0, rec.t, a))

        out = {"kinetic": at(rec.kinetic), "potential": at(rec.potential) + at(
            rec.contact_potential), "damping": at(rec.damping_work),
            "impact loss": at(rec.contact_work) - at(rec.contact_potential)}
    else:
        return None
    total = sum(out.values())
    out["energy transferred"] = rr.values.get("energy_transferred", math.nan)
    return {"t": T0, "terms": out, "initial": e0, "residual": (total - e0) / e0}


def identification_sweep(table) -> list[dict]:
    """Per e of the small-e sweep's table (compare.studies.small_e): the procedure's values and
    relative errors against the SDOF truth (M_T, K_T, xi, E), or why there are none."""
    out = []
    for r in sorted(table.to_dict("records"), key=lambda r: float(r["restitution"])):
        e = float(r["restitution"])
        if r["status"] != OK:
            out.append({"restitution": e, "status": r["status"], "reason": r["error"],
                        "errors": {}})
        elif isinstance(r.get("id_error"), str):
            out.append({"restitution": e, "status": SKIPPED, "reason": r["id_error"],
                        "T0": float(r["T0"]), "errors": {}, "values": {}})
        else:
            values = {k: float(r[f"id.{k}"]) for k in IDENT_METRICS}
            truth = {k: float(r[f"truth.{k}"]) for k in IDENT_METRICS}
            out.append({"restitution": e, "status": OK, "reason": None, "T0": float(r["T0"]),
                        "errors": {k: (values[k] - truth[k]) / truth[k] for k in values},
                        "values": values})
    return out


def record_fits(ladder) -> list[dict]:
    """:func:`fit_one` on each of ``ladder``'s rungs' records, in this process (the report
    fits every scenario's records in one process pool, compare.report.build_sections)."""
    return [fit_one(task) for task in fit_tasks(ladder)]


def fit_truth(ladder) -> dict:
    """What the full-record fit is compared with: the ``ladder``'s scenario's M_T (kg), K_T
    (N/m) and C_T (N s/m) of the two-body model (eqs 7-11) and its restitution e (1)."""
    model = two_body_model(ladder.scenario)
    return {"M_T": model.dynamic_mass, "K_T": model.equivalent_stiffness,
            "C_T": model.equivalent_damping,
            "restitution": ladder.scenario.contact.restitution}


def fit_cells(fit: dict, truth: dict) -> list[dict]:
    """The page's cells of one full-record fit (:func:`record_fits`), M_T, K_T, C_T and e:
    ``value`` (None where the record does not fix it), its 95 % interval ``low``-``high``
    (e clipped to its physical range [0, 1]), the relative ``error`` against ``truth``,
    and ``fixed``: False where the record does not fix the quantity (a one-impact record's
    range, or an e whose 95 % interval spans all of [0, 1])."""
    cells = []
    for k in ("M_T", "K_T", "C_T", "restitution"):
        lo, hi = (fit.get("ranges", {}).get(k) or fit.get("intervals", {}).get(k)
                  or (math.nan, math.nan))
        value = fit["values"].get(k, math.nan)
        fixed = k not in fit.get("ranges", {})
        if k == "restitution":
            lo, hi = max(0.0, lo), min(1.0, hi)
            fixed = fixed and not (lo <= 0.0 and hi >= 1.0)
        width = (hi - lo) / abs(value) if fixed and value and math.isfinite(value) else math.nan
        cells.append({"metric": k, "value": value if fixed else None, "low": lo, "high": hi,
                      "fixed": fixed, "truth": truth.get(k),
                      "error": fit.get("errors", {}).get(k) if fixed else None,
                      # an interval under 0.1 % of the value says nothing: not shown
                      "show_interval": not fixed or not (width < 1e-3)})
    return cells


#: The engines' comparison with each other at one rung kind, in words (the tolerance file's
#: ``engines.<kind>`` sections).
_ENGINE_STEPS = {"engine": "the engines against each other on the engine SDOF",
                 "chain": "the engines against each other on the hinged chain",
                 "pendulum": "the engines against each other with the full pendulum"}


def step_name(key: str) -> str:
    """A comparison of the tolerance file, its ``key`` (``beam``, ``engines.chain``), in
    plain words."""
    section, _, kind = key.rpartition(".")
    if section == "engines":
        return _ENGINE_STEPS.get(kind, f"the engines against each other ({kind})")
    try:
        return RungKind(kind).step
    except ValueError:
        return kind.replace("_", " ")


def not_compared_lines(entries: list[dict]) -> list[dict]:
    """The ladder's ``not_compared()`` entries (one per comparison and reason) grouped once
    per reason and metrics: ``{"metrics", "steps" (plain words, or "every comparison"),
    "reason"}``, the widest group first."""
    groups: dict = {}
    for n in entries:
        key = (n["reason"], tuple(n["metrics"]))
        groups.setdefault(key, []).append(n["kind"])
    every = {n["kind"] for n in entries}
    out = []
    for (reason, metrics), kinds in groups.items():
        steps = "every comparison" if set(kinds) == every and len(every) > 1 else \
            "; ".join(step_name(k) for k in kinds)
        out.append({"metrics": list(metrics), "steps": steps, "count": len(kinds),
                    "reason": reason[:1].upper() + reason[1:]})
    return sorted(out, key=lambda g: -g["count"])


def css(check) -> str:
    """The page's class of a checked cell: a documented finding, a flagged check, or none."""
    if check is None:
        return ""
    return "finding" if check.verdict == Verdict.FINDING else "flag" if check.verdict.flagged \
        else ""


class ScenarioSection(Section):
    """One scenario's section: its ladder table and checks, the identification against
    the truth and against e, the full-record fits, the energy ledgers and the figures."""

    template = "scenario"

    def __init__(self, ladder, sweep: list, *, figure_sink=None, fits=None):
        """One scenario's section from its finished ladder and identification sweep (no
        runs here); figures go to ``figure_sink(fig, stem) -> path``; ``fits``: its
        :func:`record_fits` when made elsewhere (None: made here)."""
        self.ladder = ladder
        self.title = f"Scenario {self.ladder.name}"
        self.anchor = f"scenario-{self.ladder.name}"
        self.ledgers = {r.rung.id: energy_ledger(r) for r in self.ladder.rungs}
        self.sweep = sweep
        self.fits = record_fits(self.ladder) if fits is None else fits
        self.mechanism = matched_loss_evidence(self.ladder)
        self.checks = self.ladder.checks()
        self.figures = {}  # name -> path of the figure file, relative to the page
        if figure_sink is not None:
            self._draw(figure_sink)

    @classmethod
    def from_runs(cls, scenario, cache, e_table=None, *, engines=None, segments=None,
                  figure_sink=None, fits=None):
        """The section of ``scenario`` from the runs in ``cache`` (a RunCache: runs it
        lacks are made here, so prefetch them first) and its small-e sweep's table
        ``e_table`` (compare.studies.small_e.small_e_sweep; None: the section has no identification
        against e); ``engines`` and ``segments`` as :func:`compare.tree.ladder.build_ladder`,
        ``figure_sink`` and ``fits`` as the constructor's."""
        kw = {} if engines is None else {"engines": engines}
        ladder = build_ladder(scenario, cache=cache, segments=segments, **kw)
        sweep = identification_sweep(e_table) if e_table is not None else []
        return cls(ladder, sweep, figure_sink=figure_sink, fits=fits)

    def _draw(self, sink):
        """Draw the figures and hand each to ``sink(fig, stem) -> path``."""
        L = self.ladder
        drawn = {"displacement": figures.displacement_figure(L),
                 "force": figures.force_figure(L),
                 "sequence": figures.sequence_figure(L)}
        ledgers = {rid: {**v, "style": figures.rung_style(L[rid].rung)}
                   for rid, v in self.ledgers.items() if v is not None}
        if ledgers:
            e0 = next(iter(ledgers.values()))["initial"]
            drawn["energy"] = summary_figures.energy_figure(ledgers, e0, L.name)
        self.figures = {name: sink(fig, f"{L.name}-{name}") for name, fig in drawn.items()}

    def _verdicts(self) -> dict:
        """(rung, metric) -> step check verdict; (rung, id metric, 'truth') for identification."""
        out = {}
        for c in self.checks:
            key = (c.rung, c.metric, c.reference)
            out[key] = c
        return out

    def context(self) -> dict:
        """The template's names: the ladder table with each cell's verdict, the
        identification rows, ledgers, fits, findings, problems and figures."""
        L = self.ladder
        verdicts = self._verdicts()
        rows = []
        for row in L.table():
            cells = []
            for cell in row["cells"]:
                r = L[cell["rung"]]
                c = verdicts.get((cell["rung"], row["metric"], r.rung.previous))
                cells.append({**cell, "verdict": c.verdict if c else "", "css": css(c),
                              "flag": bool(c and c.verdict.flagged)})
            rows.append({**row, "cells": cells})
        ident_rows = []
        for r in L.rungs:
            idr = r.identification
            cols = []
            for k in IDENT_METRICS:
                c = verdicts.get((r.rung.id, f"id_{k}", "truth"))
                cols.append({"metric": k, "value": idr.values.get(k),
                             "error": idr.errors.get(k), "verdict": c.verdict if c else "",
                             "css": css(c), "flag": bool(c and c.verdict.flagged)})
            ident_rows.append({"rung": r.rung.id, "status": idr.status, "reason": idr.reason,
                               "cols": cols})
        findings = [c for c in self.checks if c.finding]
        problems = [c for c in self.checks if c.verdict.flagged and not c.finding]
        return {
            "L": L, "rows": rows, "ident_rows": ident_rows, "truth": L.truth,
            "ident_metrics": IDENT_METRICS, "figures": self.figures,
            "rungs": L.rungs, "skips": [r for r in L.rungs if not r.ok],
            "ledgers": self.ledgers, "no_ledger": self._no_ledger(),
            "sweep": self.sweep, "fits": self.fits,
            "fits_not_fixed": any(f.get("ranges") for f in self.fits),
            "fit_rows": self._fit_rows(),
            "findings": findings, "mechanism": self.mechanism,
            "problems": problems, "not_compared": not_compared_lines(L.not_compared()),
            "unit_of": unit_of, "meaning_of": meaning_of,
            "metrics": ALL_METRICS, "OK": OK,
            "implausible": [i.text for i in implausible(L.scenario)],
        }

    def _no_ledger(self) -> str | None:
        """Why the ledger at T0 has no row (no rung that ran has a moving-together start:
        the bodies never move together on this tree), or None when it has one."""
        if any(v is not None for v in self.ledgers.values()):
            return None
        return ("No ledger at T0: on no rung that ran do the bodies move together (the "
                "impactor parts before the trunk catches up), so there is no T0 to take "
                "the energies at.")

    def _fit_rows(self) -> list[dict]:
        """The full-record fit table's rows: the truth, then each rung's cells
        (:func:`fit_cells`), or its error."""
        if not self.fits:
            return []
        truth = fit_truth(self.ladder)
        rows = []
        for f in self.fits:
            if f.get("error"):
                rows.append({"rung": f["rung"], "error": tidy(f["error"]), "e_not_fixed": False})
                continue
            cells = fit_cells(f, truth)
            rows.append({"rung": f["rung"], "cells": cells, "residual": f["residual"],
                         "explained": f["explained"], "error": None,
                         "e_not_fixed": not cells[-1]["fixed"]})
        return [{"rung": "truth", "truth": truth, "error": None, "e_not_fixed": False}] + rows

    def to_json(self) -> dict:
        """The ladder's JSON with the energy ledgers, the identification against e, the
        record fits and the mechanism."""
        out = self.ladder.to_json()
        out["energy_ledger"] = to_jsonable({k: v for k, v in self.ledgers.items()})
        out["identification_vs_e"] = to_jsonable(self.sweep)
        out["record_fits"] = to_jsonable(self.fits)
        out["mechanism"] = to_jsonable(self.mechanism)
        out["implausible_inputs"] = [i.text for i in implausible(self.ladder.scenario)]
        return out
