"""The discrepancy ladder: one scenario run as a ladder of models, one assumption per rung.

Design notes and measured figures: docs/ladder.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cache, cached_property
from types import SimpleNamespace

from treeimpact.analytic.continuum.chain_impact import converged_segments
from treeimpact.analytic.metrics import LADDER_METRICS, METRIC_UNITS
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.records import PEAK_AMBIGUITY, peak_times
from treeimpact.analytic.results import finite_number, to_jsonable

from ..runs.backends import ENGINES
from ..runs.bounds import Pair, tree_entry
from ..runs.cache import SKIPPED, Run, RunCache, Status, is_shipped, resolve_scenario
from ..runs.findings import TreePhysics
from ..runs.peaks import other_peak, within_top
from ..runs.rungs import rung_table  # (ANALYTIC_SAMPLE_STEP, Rung: public here too)
from ..runs.rungs import (  # noqa: F401
    ANALYTIC_SAMPLE_STEP,
    ENGINE_KINDS,
    Rung,
    RungKind,
    analytic_samples,
)
from ..runs.verdicts import Check, Verdict, _f, judge, load_tolerances, relative_step
from .identification import (
    IDENT_METRICS,
    IDENT_UNITS,
    RungIdentification,
    rung_identification,
    rung_truth,
)

#: The ladder's metrics: analytic.metrics.LADDER_METRICS and the identified ones as ``id_``.
ALL_METRICS = LADDER_METRICS + tuple(f"id_{k}" for k in IDENT_METRICS)


def unit_of(metric: str) -> str:
    """The unit of a ladder ``metric`` (an ``id_`` one: the identified quantity's)."""
    if metric.startswith("id_"):
        return IDENT_UNITS[metric[3:]][0]
    return METRIC_UNITS[metric][0]


def meaning_of(metric: str) -> str:
    """What a ladder ``metric`` means, in a few words."""
    if metric.startswith("id_"):
        return IDENT_UNITS[metric[3:]][1]
    return METRIC_UNITS[metric][1]


def chain_segments(scenario: Scenario, segments: int | None = None) -> int:
    """Segments of the hinged trunk and the rod: ``segments``, or
    analytic.continuum.chain_impact.converged_segments of ``scenario`` (the smallest N meeting
    the static stiffness and first two frequencies within 0.5 % of the beam whose exact chain
    and exact rod are within three quarters of each [step.chain] and [step.rod] tolerance of the exact
    beam; docs/trunk-models.md "Segments per tree")."""
    if segments is not None:
        return int(segments)
    steps = load_tolerances().get("step", {})
    judged = tuple((trunk, metric, float(e["rel"])) for trunk in ("chain", "rod")
                   for metric, e in steps.get(trunk, {}).items()
                   if isinstance(e, dict) and "rel" in e)
    return converged_segments(scenario, judged)


def ladder_rungs(scenario, *, engines=ENGINES, segments: int | None = None) -> list[Rung]:
    """The rungs of one scenario, in ladder order (:func:`compare.runs.rungs.rung_table` of the
    ``engines`` with the scenario's chain ``segments`` and the analytic record's
    sampling)."""
    scen = resolve_scenario(scenario)
    samples = analytic_samples(scen.t_end)
    return rung_table(engines, segments=chain_segments(scen, segments),
                      analytic_options=(("samples", samples),))


# --------------------------------------------------------------------------- the ladder


@dataclass
class RungResult:
    """One rung's run: the ``rung``, its ``run``, its ladder ``values`` (metric -> SI value,
    NaN when missing), the procedure's ``identification`` and the times (s) of x(t)'s
    near-equal maxima (``peaks``)."""

    rung: Rung
    run: Run
    values: dict = field(default_factory=dict)  # metric -> value (NaN when missing)
    identification: RungIdentification | None = None
    peaks: list = field(default_factory=list)  # s: the times of x(t)'s near-equal maxima

    @property
    def ok(self) -> bool:
        """Whether the rung ran (its run's status OK)."""
        return self.run.ok

    @property
    def status(self) -> Status:
        """The run's status."""
        return self.run.status

    @property
    def reason(self) -> str | None:
        """Why the run did not finish, or None."""
        return self.run.reason

    @property
    def result(self):
        """The run's SimulationResult (None when it did not finish)."""
        return self.run.result


@dataclass
class Ladder:
    """One scenario's ladder: every rung's values, steps and checks (docs/ladder.md).

    Attributes:
        scenario: the :class:`Scenario` it ran.
        rungs: each rung's result, in ladder order (``ladder["soft"]`` finds one by id).
        truth: the scenario's own 1-DOF model's M_T (kg), K_T (N/m), xi (1), E (Pa).
        tolerances: the tolerances it was judged against (compare/runs/tolerances.toml).
    """

    scenario: Scenario
    rungs: list  # RungResult, ladder order
    truth: dict
    tolerances: dict

    def __getitem__(self, rung_id: str) -> RungResult:
        for r in self.rungs:
            if r.rung.id == rung_id:
                return r
        raise KeyError(rung_id)

    @property
    def name(self) -> str:
        """The scenario's name."""
        return self.scenario.name

    @cached_property
    def physics(self) -> TreePhysics:
        """The tree's quantities that decide which findings apply (never its name)."""
        return TreePhysics.of(self.scenario)

    def value(self, rung_id: str, metric: str) -> float:
        """The value of ``metric`` on the rung ``rung_id`` (SI; NaN when missing)."""
        return self[rung_id].values.get(metric, math.nan)

    def step(self, rung_id: str, metric: str) -> float:
        """The relative change of ``metric`` from the previous rung to ``rung_id``
        (:func:`compare.runs.verdicts.relative_step`; NaN on the first rung)."""
        r = self[rung_id]
        if r.rung.previous is None:
            return math.nan
        return relative_step(r.values.get(metric, math.nan),
                             self[r.rung.previous].values.get(metric, math.nan))

    def _undefined(self, section: str, kind: str, metric: str) -> bool:
        entry = self.tolerances.get(section, {}).get(kind, {}).get(metric)
        return bool(entry and entry.get("undefined"))

    def not_compared(self) -> list[dict]:
        """The (step kind, metrics, reason) the tolerance file marks ``undefined``: quantities
        the step's models do not both define robustly, so no check is made (the ladder
        table still shows their values). Only kinds present in this ladder."""
        kinds = {r.rung.kind for r in self.rungs if r.rung.previous is not None}
        kinds |= {f"engines.{r.rung.kind}" for r in self.rungs}
        out = {}
        for section in ("step", "engines"):
            for kind, metrics in self.tolerances.get(section, {}).items():
                name = kind if section == "step" else f"engines.{kind}"
                if name not in kinds:
                    continue
                for metric, entry in metrics.items():
                    if entry.get("undefined"):
                        out.setdefault((name, self._shown(entry)["reason"]), []).append(metric)
        return [{"kind": k, "metrics": ms, "reason": why} for (k, why), ms in out.items()]

    def step_check(self, rung_id: str, metric: str) -> Check:
        """The check of ``metric``'s step from the previous rung to ``rung_id`` against the
        tolerance file's entry for the rung's kind (ambiguous where x(t) has near-equal
        maxima on either rung)."""
        r = self[rung_id]
        prev = r.rung.previous
        entry = cache(lambda: self._entry("step", r.rung.kind, metric, rung_id, prev))
        ambiguous = self._ambiguous_peak("step", r.rung.kind, rung_id, prev, metric, entry)
        if ambiguous is not None:
            return ambiguous
        return judge(self.name, rung_id, r.rung.kind, metric, self.value(rung_id, metric), prev,
                     self.value(prev, metric), entry(), self.tolerances, self.physics,
                     Pair(self.scenario, self.physics, metric, r, self[prev]))

    def _entry(self, section: str, kind: str, metric: str, rung_id: str, reference: str):
        """The tolerance file's entry for ``metric`` of the ``section``'s ``kind`` as it
        applies to this tree: a per-tree bound evaluated on the two rungs
        (:func:`compare.runs.bounds.tree_entry`)."""
        entry = self._shown(self.tolerances.get(section, {}).get(kind, {}).get(metric))
        return tree_entry(entry, Pair(self.scenario, self.physics, metric, self[rung_id],
                                      self[reference]))

    @cached_property
    def shipped(self) -> bool:
        """Whether this is one of the shipped trees, input for input (its name alone is not
        enough: a user's tree may share it): only then do reasons quote the shipped trees'
        measurements (an entry's ``measured``)."""
        return is_shipped(self.scenario)

    def _shown(self, entry: dict | None) -> dict | None:
        """``entry`` with the reason this tree is shown: its physics, and the shipped trees'
        measurements (``measured``) on a shipped tree only."""
        if not entry or "measured" not in entry:
            return entry
        reason = f"{entry['reason']} ({entry['measured']})" if self.shipped else entry["reason"]
        return {**entry, "reason": reason}

    def _ambiguous_peak(self, section: str, kind: str, rung_id: str, reference: str,
                        metric: str, entry) -> Check | None:
        """t_xmax compared between a record with one clear maximum and one whose x(t) has a
        second maximum within 5 % of the largest (analytic.records.peak_times), or between
        two records with near-equal maxima whose largest is not the same peak (the peak of
        one nearest the other's t_xmax is not its own maximum): flagged 'ambiguous', not
        judged (which peak wins flips with small changes); and where each record stays
        within the comparison's x_max tolerance of its maximum at the other's t_xmax
        (:meth:`_flat_top`). Otherwise judged as usual; ``section`` and ``kind`` name the
        comparison's entries (``step``/``engines``, the rung kind), ``entry()`` gives the
        metric's own entry as it applies to the tree (evaluated at most once, by the caller's
        cache, and only where needed)."""
        if metric != "t_xmax":
            return None
        a, b = self[rung_id].peaks, self[reference].peaks
        value, ref = self.value(rung_id, metric), self.value(reference, metric)
        if (len(a) > 1) == (len(b) > 1) and not other_peak(a, b, value, ref):
            return self._flat_top(section, kind, rung_id, reference, entry())
        which, times = (rung_id, a) if len(a) > 1 else (reference, b)
        return Check(self.name, rung_id, metric, _f(value), reference, _f(ref),
                     relative_step(value, ref), None, Verdict.AMBIGUOUS,
                     f"x(t) of {which} has maxima within {100 * PEAK_AMBIGUITY:.0f} % of each other at "
                     + ", ".join(f"{1e3 * s:.1f}" for s in times) + " ms: the time of the "
                     "maximum is not a robust quantity")

    def _flat_top(self, section: str, kind: str, rung_id: str, reference: str,
                  own: dict | None) -> Check | None:
        """t_xmax flagged 'ambiguous' where the two times differ beyond their tolerance and
        x(t) of each record, at the other's time of the maximum, is within the comparison's
        x_max tolerance of its own maximum (a flat top: x_max resolves no time within it);
        None otherwise (``own``: t_xmax's entry as it applies to the tree; the tolerances are
        the entries', per tree where they name a bound)."""
        times = [self.value(r, "t_xmax") for r in (rung_id, reference)]
        if own and "rel" in own and abs(relative_step(*times)) <= float(own["rel"]):
            return None  # the times agree within their own tolerance: judged as usual
        entry = self._entry(section, kind, "x_max", rung_id, reference)
        tau = float(entry["rel"]) if entry and "rel" in entry else 0.0
        runs = [self[r].result for r in (rung_id, reference)]
        if tau <= 0 or any(r is None or r.trajectory is None for r in runs) or not (
                within_top(runs[0].trajectory, times[1], tau)
                and within_top(runs[1].trajectory, times[0], tau)):
            return None
        value, ref = times
        return Check(self.name, rung_id, "t_xmax", _f(value), reference, _f(ref),
                     relative_step(value, ref), None, Verdict.AMBIGUOUS,
                     f"x(t) of both stays within the x_max tolerance ({100 * tau:.2g} %) of its "
                     f"maximum from {1e3 * min(times):.2f} to {1e3 * max(times):.2f} ms: x_max "
                     "resolves no time of the maximum within that flat top")

    def identification_check(self, rung_id: str, metric: str) -> Check:
        """The identified value of ``metric`` on the rung ``rung_id`` against the truth,
        judged on the Newton record the procedure was derived for. On other rungs the
        identification table shows the error against the truth without a check (the file's
        ``identification_reported`` reason)."""
        r = self[rung_id]
        truth = SimpleNamespace(values={f"id_{metric}": self.truth[metric]}, result=None)
        entry = tree_entry(self._shown(self.tolerances.get("identification", {}).get(metric)),
                           Pair(self.scenario, self.physics, f"id_{metric}", r, truth))
        return judge(self.name, rung_id, r.rung.kind, f"id_{metric}",
                     r.values.get(f"id_{metric}", math.nan), "truth", self.truth[metric],
                     entry, self.tolerances, self.physics)

    def engines_check(self, kind: str, metric: str) -> Check | None:
        """MuJoCo against Bullet on ``metric`` at one rung ``kind`` (engine, chain or
        pendulum); None unless the ladder has both."""
        ids = [r.rung.id for r in self.rungs if r.rung.kind == kind]
        if len(ids) != 2:
            return None
        entry = cache(lambda: self._entry("engines", kind, metric, ids[1], ids[0]))
        ambiguous = self._ambiguous_peak("engines", kind, ids[1], ids[0], metric, entry)
        if ambiguous is not None:
            return ambiguous
        return judge(self.name, ids[1], f"engines-{kind}", metric, self.value(ids[1], metric),
                     ids[0], self.value(ids[0], metric), entry(), self.tolerances, self.physics)

    def checks(self) -> list[Check]:
        """Every comparison of the ladder: steps, identification, engines against each other."""
        out = []
        for r in self.rungs:
            if not r.ok:
                continue
            if r.rung.previous is not None and self[r.rung.previous].ok:
                out += [self.step_check(r.rung.id, m) for m in ALL_METRICS
                        if not self._undefined("step", r.rung.kind, m)]
            if r.identification.ok and r.rung.kind == RungKind.NEWTON:
                out += [self.identification_check(r.rung.id, m) for m in IDENT_METRICS]
        for kind in ENGINE_KINDS:
            ids = [r for r in self.rungs if r.rung.kind == kind]
            if len(ids) == 2 and all(r.ok for r in ids):
                out += [self.engines_check(kind, m) for m in ALL_METRICS
                        if not self._undefined("engines", kind, m)]
        return out

    def table(self) -> list[dict]:
        """The ladder table: per metric, every rung's value and step from its previous rung."""
        rows = []
        for m in ALL_METRICS:
            cells = []
            for r in self.rungs:
                cells.append({"rung": r.rung.id, "value": r.values.get(m, math.nan),
                              "step": self.step(r.rung.id, m), "status": r.status})
            rows.append({"metric": m, "unit": unit_of(m), "meaning": meaning_of(m),
                         "truth": self.truth.get(m[3:], math.nan) if m.startswith("id_")
                         else math.nan, "cells": cells})
        return rows

    def to_json(self) -> dict:
        """The ladder as JSON: scenario, inputs, truth, each rung (its values, steps and
        identification) and every check."""
        return to_jsonable({
            "scenario": self.name,
            "inputs": self.scenario.to_dict(),
            "truth": self.truth,
            "rungs": [{
                "id": r.rung.id, "level": r.rung.level, "kind": r.rung.kind,
                "assumption": r.rung.assumption, "backend": r.rung.backend,
                "options": dict(r.rung.options), "previous": r.rung.previous,
                "status": r.status, "reason": r.reason, "wall_s": r.run.wall_s,
                "model": r.result.model if r.ok else None,
                "values": r.values,
                "steps": {m: self.step(r.rung.id, m) for m in ALL_METRICS},
                "identification": r.identification.to_json(),
            } for r in self.rungs],
            "checks": [c.to_json() for c in self.checks()],
        })


def rung_values(result, identification: RungIdentification) -> dict:
    """A rung's ladder values: the LADDER_METRICS of ``result`` and, as ``id_`` keys, the
    ``identification``'s values (NaN where it did not run)."""
    vals = {m: _f(result.metrics.get(m)) for m in LADDER_METRICS}
    for k in IDENT_METRICS:
        vals[f"id_{k}"] = _f(identification.values.get(k)) if identification.ok else math.nan
    return vals


def prefetch_ladders(cache: RunCache, scenarios, *, engines=None, segments=None,
                     workers: int | None = None, progress: bool = False) -> None:
    """Run every rung of the ``scenarios``' ladders (with ``engines`` and ``segments`` as
    :func:`build_ladder`) into ``cache`` on a process pool of ``workers``
    (:meth:`compare.runs.cache.RunCache.prefetch`; ``progress``: a bar on stderr);
    :func:`build_ladder` then finds them cached."""
    engines = ENGINES if engines is None else engines
    cache.prefetch([(s, r.backend, dict(r.options)) for s in scenarios
                    for r in ladder_rungs(s, engines=engines, segments=segments)],
                   workers=workers, progress=progress)


def build_ladder(scenario, *, cache: RunCache | None = None, engines=ENGINES,
                 segments: int | None = None, tolerances: dict | None = None) -> Ladder:
    """Run (or fetch from ``cache``) every rung of one scenario and assemble the ladder:
    the rungs of ``engines``, the chain of ``segments`` (None: the default), judged against
    ``tolerances`` (None: compare/runs/tolerances.toml)."""
    scen = resolve_scenario(scenario)
    cache = RunCache() if cache is None else cache
    tol = load_tolerances() if tolerances is None else tolerances
    out = []
    for rung in ladder_rungs(scen, engines=engines, segments=segments):
        run = cache.run(scen, rung.backend, **dict(rung.options))
        rr = RungResult(rung, run)
        if run.ok:
            rr.identification = rung_identification(run, scen)
            rr.values = rung_values(run.result, rr.identification)
            tr = run.result.trajectory
            rr.peaks = peak_times(tr.t, tr.x) if tr is not None else []
        else:
            rr.values = {m: math.nan for m in ALL_METRICS}
            rr.identification = RungIdentification(SKIPPED, f"rung not run: {run.reason}")
        out.append(rr)
    truth = rung_truth(scen)  # the tree's own 1-DOF model, whichever impactor strikes it
    return Ladder(scen, out, truth, tol)


# --------------------------------------------------------------------------- failure table


def _fmt(v) -> str:
    if isinstance(v, str):
        return v
    if v is None or not finite_number(v):
        return "n/a"
    return f"{v:.5g}"


def failure_table(ladder: Ladder, checks: list[Check]) -> str:
    """The compact table a failing check prints, one row per check of ``checks`` on
    ``ladder``: metric, each rung's value, the compared pair, relative difference,
    tolerance and reason."""
    rung_ids = [r.rung.id for r in ladder.rungs]
    head = ["metric", "unit", *rung_ids, "checked", "vs", "rel diff", "tolerance", "verdict",
            "reason"]
    rows = [head]
    for c in checks:
        vals = [_fmt(ladder.value(rid, c.metric)) if ladder[rid].ok else ladder[rid].status
                for rid in rung_ids]
        tol = (f"band [{c.band[0]:+.3g}, {c.band[1]:+.3g}]" if c.band else
               ("-" if c.tolerance is None else f"{c.tolerance:.3g}"))
        rows.append([c.metric, unit_of(c.metric), *vals, c.rung, c.reference,
                     "n/a" if not math.isfinite(c.rel_diff) else f"{c.rel_diff:+.3%}", tol,
                     c.verdict, c.reason])
    widths = [max(len(str(r[i])) for r in rows) for i in range(len(head) - 1)]
    lines = []
    for r in rows:
        lines.append("  ".join(str(c).ljust(w) for c, w in zip(r[:-1], widths)) + "  " + r[-1])
    return f"scenario {ladder.name}\n" + "\n".join(lines)
