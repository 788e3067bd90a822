"""One source for every number the README and docs/ quote (issue 26), and the pages checked
against it.

Where the numbers come from:

* ``docs/numbers.json``: the results of the code, derived from a report (``make report``) by
  ``python -m treeimpact.compare.docs numbers REPORT_DIR``, which also reruns the cheap
  part (:func:`cheap_numbers`: the shipped trees' analytic rungs and mechanism, the beam
  studies, ``treeimpact contact``'s collisions, the models at the contact fitted to the
  paper's trees, the code's constants; seconds) and says where the report disagrees with it;
  it keeps only the keys the pages quote (and what the tests read), so a new mark needs
  ``numbers`` rerun;
* ``docs/results/contact-fit.json``: the output of ``treeimpact paper --fit-contact --json``;
* ``docs/results/identify-validation.json``: the identification's validation set and accuracy
  (``tests/data/identify/make_records.py --evaluate --numbers FILE`` and ``--accuracy N``),
  its numbers under ``identify.``;
* ``benchmarks/results/*.json``: each benchmark's own results file (``make benchmark``,
  ``benchmarks/_results.py``), with the machine and its load; timings are quoted from there
  only.

How a page quotes one (the markdown conventions, invisible when rendered):

* ``+8.6 %<!-- check: gap_pct.x_max.open-center -->``: the number (or list of numbers: a
  range ``57-213``, ``-12..-14``, ``9, 21 and 33``, ``+8.5 / +17.8``) just before the
  comment, a unit word allowed between, is the value of the key (a number, or a list of as
  many; one number may stand for a [min, max] range whose ends both round to it) rounded to
  the digits the page prints: it may differ by at most half a unit of its last digit (the
  page quotes a rounded value; a finer difference is the rounding itself). ``check-max``:
  the page's number is an upper bound of the value ("within 0.4 %"), ``check-min`` a lower
  bound; `` ~10%`` after the key allows that relative difference instead (an "about").
* ``<!-- BEGIN generated: NAME -->`` ... ``<!-- END generated: NAME -->``: a block written by
  ``python -m treeimpact.compare.docs write`` from the sources (:data:`GENERATED`); the
  check regenerates it in memory and compares it number by number (as floats, at the
  digits printed) and word by word.

``python -m treeimpact.compare.docs check`` lists every quoted number and block that
drifted; ``tests/test_doc_numbers.py`` fails on one. SI units in the sources; keys say their
unit where it is not SI (``_pct``, ``_ms``, ``_kg``) and :data:`DISPLAY` gives the rungs'
values' (``value.*``).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NUMBERS = ROOT / "docs" / "numbers.json"
CONTACT_FIT = ROOT / "docs" / "results" / "contact-fit.json"
IDENTIFY_VALIDATION = ROOT / "docs" / "results" / "identify-validation.json"
BENCHMARKS = ROOT / "benchmarks" / "results"
#: The shipped trees, in the order the pages list them.
TREES = ("open-center", "central-leader", "realistic-crown")
#: How the rungs' values are quoted: metric -> (scale from SI, unit).
DISPLAY = {"T0": (1e3, "ms"), "x0": (1e3, "mm"), "V": (1.0, "m/s"), "x_max": (1e3, "mm"),
           "t_xmax": (1e3, "ms"), "t_sep": (1e3, "ms"), "impact_loss": (1.0, "J"),
           "energy_transferred": (1.0, "J"), "theta_b": (180.0 / math.pi, "deg"),
           "energy_delivered": (1.0, "J"), "contact_dissipation": (1.0, "J"),
           "rebound_energy": (1.0, "J"), "impulse": (1.0, "N s"), "peak_force": (1e-3, "kN"),
           "contact_episodes": (1.0, "1"), "crown_peak": (1e3, "mm"),
           "crown_peak_acceleration": (1.0, "m/s^2")}
#: Relative difference allowed between a report's numbers and the cheap part rerun beside
#: it by ``numbers`` (:func:`write_numbers`: one machine, one BLAS kernel, so deterministic
#: runs; the file keeps 8 significant digits). Across machines the numbers are compared at
#: the digits the pages print instead (:func:`check_now`): another CPU's BLAS kernel moves
#: the last bits, and a difference of nearly equal values (beam.*.vs48_pct) by 1e-5 of
#: itself.
RECOMPUTE_REL = 1e-6
#: Significant digits kept in docs/numbers.json.
DIGITS = 8


# --------------------------------------------------------------------------- helpers


def _finite(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _round(v):
    if isinstance(v, list):
        return [_round(x) for x in v]
    return float(f"{v:.{DIGITS}g}") if _finite(v) else v


def _span(values) -> list | None:
    vals = [v for v in values if _finite(v)]
    return [min(vals), max(vals)] if vals else None


def _put(out: dict, key: str, value) -> None:
    if value is None:
        return
    if isinstance(value, list):
        if not value or not all(_finite(v) for v in value):
            return
    elif not _finite(value):
        return
    out[key] = _round(value)


def _per_tree(out: dict, key: str, by_tree: dict, *, spans: bool = True) -> None:
    """key.<tree> for each tree, key.trees (the list in :data:`TREES` order, when every
    tree has it), key (the [min, max] span) and abs.key (the span of |value|)."""
    for t, v in by_tree.items():
        _put(out, f"{key}.{t}", v)
        if spans and _finite(v) and v < 0:
            _put(out, f"abs.{key}.{t}", abs(v))
        elif spans:
            _put(out, f"abs.{key}.{t}", v)
    vals = [by_tree.get(t) for t in TREES]
    if all(_finite(v) for v in vals):
        _put(out, f"{key}.trees", vals)
    if spans:
        _put(out, key, _span(by_tree.values()))
        _put(out, f"abs.{key}", _span([abs(v) for v in by_tree.values() if _finite(v)]))


# --------------------------------------------------------------------------- the view
# One shape for what a report's JSON and freshly run ladders say, so that the numbers of
# both are derived by the same code.


def _rung_group(rung_id: str, kind: str, backend: str) -> str:
    """A rung's name across trees: its kind, prefixed by the engine for engine rungs
    (``mujoco.chain`` for mujoco-chain10 and mujoco-chain12)."""
    return f"{backend}.{kind}" if backend in ("mujoco", "bullet") else kind


def view_from_report(report: dict) -> dict:
    """The view of a report's JSON (``report.json`` of ``treeimpact report``)."""
    trees = {}
    answer = {a["scenario"]: a for a in report["answer"]["one_dof"] if a.get("available")}
    for name, sc in report["scenarios"].items():
        rungs = {}
        for r in sc["rungs"]:
            if r["status"] != "ok":
                continue
            rungs[_rung_group(r["id"], r["kind"], r["backend"])] = {
                "id": r["id"], "previous": r["previous"], "values": r["values"],
                "steps": r["steps"], "model": r["model"], "first_contact": None}
        pad = (answer.get(name) or {}).get("pad") or {}
        if "contact" in rungs and pad.get("one_dof"):
            rungs["contact"]["first_contact"] = pad["one_dof"]["first_contact_duration"]
        if "beam" in rungs and pad.get("continuum"):
            rungs["beam"]["first_contact"] = pad["continuum"]["first_contact_duration"]
        trees[name] = {"rungs": rungs, "truth": sc["truth"], "mechanism": sc.get("mechanism"),
                       "answer": answer.get(name), "record_fits": sc.get("record_fits")}
    s = report["summary"]
    return {"trees": trees, "verdicts": s.get("verdicts"),
            "scans": (s.get("contact") or {}).get("scans")}


def view_from_ladders(ladders) -> dict:
    """The view of ladders run now (:func:`compare.ladder.build_ladder`), with the report's
    own answer and mechanism functions."""
    from types import SimpleNamespace

    from .mechanism import matched_loss_evidence
    from .report.answer import one_dof_answer
    from .verdicts import relative_step

    answers = {a["scenario"]: a for a in one_dof_answer([SimpleNamespace(ladder=L, fits=[])
                                                         for L in ladders])
               if a.get("available")}
    trees = {}
    for L in ladders:
        rungs = {}
        for r in L.rungs:
            if not r.ok:
                continue
            prev = r.rung.previous
            steps = {m: (relative_step(v, L[prev].values.get(m, math.nan)) if prev else None)
                     for m, v in r.values.items()}
            rungs[_rung_group(r.rung.id, str(r.rung.kind), r.rung.backend)] = {
                "id": r.rung.id, "previous": prev, "values": dict(r.values), "steps": steps,
                "model": dict(r.result.model),
                "first_contact": r.result.metrics.get("first_contact_duration")}
        trees[L.name] = {"rungs": rungs, "truth": dict(L.truth),
                         "mechanism": matched_loss_evidence(L), "answer": answers.get(L.name)}
    return {"trees": trees, "verdicts": None, "scans": None}


def cheap_ladders():
    """The shipped trees' ladders without the engines (analytic, soft, beam, Timoshenko,
    the effective-mass convention): about 2 s."""
    from .ladder import build_ladder

    return [build_ladder(t, engines=()) for t in TREES]


# --------------------------------------------------------------------------- derivations


def from_view(view: dict) -> dict:
    """Every number the pages may quote from a view (display units; see the key names)."""
    out: dict = {}
    trees = view["trees"]
    groups = sorted({g for t in trees.values() for g in t["rungs"]})
    metrics = sorted({m for t in trees.values() for r in t["rungs"].values()
                      for m in r["values"]})
    for g in groups:
        for m in metrics:
            scale = DISPLAY.get(m, (1.0, ""))[0]
            vals, steps = {}, {}
            for name, t in trees.items():
                r = t["rungs"].get(g)
                if r is None:
                    continue
                v = r["values"].get(m)
                vals[name] = scale * v if _finite(v) else None
                s = (r["steps"] or {}).get(m)
                steps[name] = 100.0 * s if _finite(s) else None
            _per_tree(out, f"value.{g}.{m}", vals)
            if any(_finite(v) for v in steps.values()):
                _per_tree(out, f"step_pct.{g}.{m}", steps)
    # both engines together (a range over MuJoCo and Bullet and the trees)
    for kind in ("engine", "chain", "pendulum"):
        for m in metrics:
            steps = [100.0 * r["steps"][m] for t in trees.values()
                     for e in ("mujoco", "bullet") for r in [t["rungs"].get(f"{e}.{kind}")]
                     if r is not None and _finite((r["steps"] or {}).get(m))]
            _put(out, f"step_pct.engines.{kind}.{m}", _span(steps))
            scale = DISPLAY.get(m, (1.0, ""))[0]
            _put(out, f"value.engines.{kind}.{m}", _span([
                scale * r["values"][m] for t in trees.values() for e in ("mujoco", "bullet")
                for r in [t["rungs"].get(f"{e}.{kind}")]
                if r is not None and _finite(r["values"].get(m))]))
            _put(out, f"abs.step_pct.engines.{kind}.{m}", _span([abs(s) for s in steps]))
    # MuJoCo against Bullet on the same rung
    for kind in ("engine", "chain", "pendulum"):
        for m in metrics:
            diffs = []
            for t in trees.values():
                a, b = t["rungs"].get(f"mujoco.{kind}"), t["rungs"].get(f"bullet.{kind}")
                if a and b and _finite(a["values"].get(m)) and _finite(b["values"].get(m)) \
                        and a["values"][m]:
                    diffs.append(abs(100.0 * (b["values"][m] / a["values"][m] - 1.0)))
            _put(out, f"engines_agree_pct.{kind}.{m}", _span(diffs))
    for name, t in trees.items():
        rungs = t["rungs"]
        for g, r in rungs.items():
            if _finite(r.get("first_contact")):
                out[f"first_contact_ms.{g}.{name}"] = _round(1e3 * r["first_contact"])
            for key in ("effective_mass", "pad_damping_ratio", "contact_damping"):
                if _finite(r["model"].get(key)):
                    out[f"model.{g}.{key}.{name}"] = _round(r["model"][key])
    for g in groups:
        for key in ("effective_mass", "pad_damping_ratio"):
            _put(out, f"model.{g}.{key}", _span([out.get(f"model.{g}.{key}.{t}")
                                                  for t in trees]))
        _put(out, f"first_contact_ms.{g}", _span([out.get(f"first_contact_ms.{g}.{t}")
                                                  for t in trees]))
    # the convention rung recalibrates only the pad's damping: how much it drops
    drops = {t: out.get(f"model.beam.contact_damping.{t}", math.nan)
             / out.get(f"model.convention.contact_damping.{t}", math.nan) for t in trees}
    _per_tree(out, "pad_damping_drop", drops)
    # the answer table: the continuum's gap to the paper's 1-DOF model
    ratios = []
    for name, t in trees.items():
        a = t.get("answer")
        if not a:
            continue
        for m, row in a["metrics"].items():
            out[f"gap_pct.{m}.{name}"] = _round(100.0 * row["rel"])
            if m in ("peak_force", "crown_peak_acceleration") and row["flexible"]:
                ratio = row["one_dof"] / row["flexible"]
                out[f"ratio.{m}.{name}"] = _round(ratio)
                ratios.append(ratio)
    if trees and all(t.get("answer") for t in trees.values()):
        for m in next(iter(trees.values()))["answer"]["metrics"]:
            _per_tree(out, f"gap_pct.{m}", {n: out.get(f"gap_pct.{m}.{n}") for n in trees})
    _put(out, "ratio.force_and_acceleration", _span(ratios))
    # the scenarios' own 1-DOF model (the identification's truth)
    for k in ("M_T", "K_T", "b", "omega_n", "xi"):
        _per_tree(out, f"truth.{k}", {n: t["truth"].get(k) for n, t in trees.items()})
    # the paper's identification procedure on the exact (Newton) record
    errs = {}
    for name, t in trees.items():
        r = t["rungs"].get("newton")
        if r and _finite(r["values"].get("id_M_T")) and _finite(t["truth"].get("M_T")):
            errs[name] = 100.0 * (r["values"]["id_M_T"] / t["truth"]["M_T"] - 1.0)
    _per_tree(out, "ident_error_pct.M_T", errs)
    _put(out, "ident_error_pct.M_T.measured_trees",
         _span([errs.get("open-center"), errs.get("central-leader")]))
    # the mechanism: the 1-DOF model with the continuum's loss (docs/whole-event-metrics.md)
    for name, t in trees.items():
        mech = t.get("mechanism")
        if not mech or mech.get("error"):
            continue
        out[f"mechanism.e_star.{name}"] = _round(mech["matched_restitution"])
        for row in mech["rows"]:
            out[f"mechanism.gap_pct.{row['metric']}.{name}"] = _round(100.0 * row["gap"])
            out[f"mechanism.matched_gap_pct.{row['metric']}.{name}"] = _round(
                100.0 * row["matched_gap"])
    for m in ("energy_delivered", "x_max", "crown_peak"):
        vals = [out.get(f"mechanism.matched_gap_pct.{m}.{n}") for n in trees]
        _put(out, f"abs.mechanism.matched_gap_pct.{m}",
             _span([abs(v) for v in vals if v is not None]))
    # the exact 1-DOF model fitted to each rung's record (the report's record fits)
    sdof, flexible = [], []
    for name, t in trees.items():
        ids = {r["id"]: g for g, r in t["rungs"].items()}
        for f in t.get("record_fits") or []:
            g = ids.get(f.get("rung"), "")
            if not f.get("errors"):
                continue
            if g in ("newton", "contact") or g.endswith(".engine"):
                sdof += [abs(100.0 * v) for v in f["errors"].values() if _finite(v)]
                out.setdefault("record_fit.sdof_explained", 0)
                out["record_fit.sdof_explained"] += int(bool(f.get("explained")))
                out.setdefault("record_fit.sdof_fits", 0)
                out["record_fit.sdof_fits"] += 1
            else:
                flexible.append(bool(f.get("explained")))
    if sdof:
        out["record_fit.sdof_max_error_pct"] = _round(max(sdof))
    if flexible:
        out["record_fit.flexible_fits"] = len(flexible)
        out["record_fit.flexible_explained"] = sum(flexible)
    # the whole run's checks
    verdicts = view.get("verdicts")
    if verdicts:
        total = sum(verdicts.values())
        out["checks.total"] = total
        for k, v in verdicts.items():
            out[f"checks.{k}"] = v
            out[f"checks.{k}_pct"] = _round(100.0 * v / total)
        out.setdefault("checks.n/a", 0)
    # the contact scan: from which pad duration the 1-DOF model is within the tolerance
    scans = view.get("scans") or {}
    for name, s in scans.items():
        longest = 1e3 * s["durations"][-1]
        out["scan.longest_ms"] = _round(longest)
        out["scan.shortest_ms"] = _round(1e3 * s["durations"][0])
        out["scan.points"] = len(s["durations"])
        out["scan.range_ms"] = _round([1e3 * s["durations"][0], longest])
        for m, d in s["shortest"].items():
            if d is None:
                out[f"scan.{m}.{name}.not_up_to_ms"] = _round(longest)
            else:
                out[f"scan_ms.{m}.{name}"] = _round(1e3 * d)
    for m in {m for s in scans.values() for m in s["shortest"]}:
        _put(out, f"scan_ms.{m}", _span([out.get(f"scan_ms.{m}.{n}") for n in scans]))
        vals = [out.get(f"scan_ms.{m}.{n}") for n in TREES]
        if all(v is not None for v in vals):
            _put(out, f"scan_ms.{m}.trees", vals)
    return out


def from_small_e(trees: dict) -> dict:
    """The small-e answer (compare.small_e; report.json's answer.small_e): per approximation
    and tree the largest e it holds up to (1, rounded down to 0.01 as the page prints it),
    its error at e = 0 and at the tree's own e (%), and their spans over the trees."""
    out: dict = {}
    for tree, answers in trees.items():
        for name, a in answers.items():
            out[f"small_e.{name}.holds_up_to_e.{tree}"] = _round(
                math.floor(100.0 * a["holds_up_to_e"] + 1e-9) / 100.0)
            for key, v in (("error_at_zero_pct", a["error_at_zero"]),
                           ("error_at_e_pct", a["error_at_e"])):
                if _finite(v):
                    out[f"small_e.{name}.{key}.{tree}"] = _round(100.0 * v)
    names = {k.split(".")[1] for k in out}
    for name in names:
        for key in ("holds_up_to_e", "error_at_zero_pct", "error_at_e_pct"):
            _put(out, f"small_e.{name}.{key}",
                 _span([out.get(f"small_e.{name}.{key}.{t}") for t in trees]))
    return out


def small_e_now() -> dict:
    """:func:`from_small_e` of the shipped trees computed now (compare.small_e, in this
    process: a few seconds)."""
    from .studies.small_e import small_e_answer, small_e_table

    return from_small_e({t: small_e_answer(_scenario(t), small_e_table(t)) for t in TREES})


def _scenario(name: str):
    from treeimpact.analytic.model.scenario import load_scenario

    return load_scenario(name)


def from_sensitivity(report: dict) -> dict:
    """The answer's ranges over the unmeasured inputs (the study's Morris screening)."""
    out: dict = {}
    for a in report["answer"]["one_dof"]:
        for key, sv in (a.get("sensitivity") or {}).items():
            name = key.split(".", 1)[1]
            out[f"sensitivity_pct.{name}.{a['scenario']}"] = _round(
                [100.0 * sv["low"], 100.0 * sv["high"]])
    for name in {k.split(".")[1] for k in out}:
        rows = [out.get(f"sensitivity_pct.{name}.{t}") for t in TREES]
        rows = [r for r in rows if r]
        _put(out, f"sensitivity_pct.{name}.low", _span([r[0] for r in rows]))
        _put(out, f"sensitivity_pct.{name}.high", _span([r[1] for r in rows]))
    return out


def from_study(study: dict) -> dict:
    """The default study's validity summaries (``study.json`` of ``make report``'s study):
    per target and metric, the share of cells within the tolerance (%) and the worst gap
    (%); the engines' chains against the beam across both engines."""
    out: dict = {}
    engines: dict = {}
    for v in study.get("validity", []):
        for r in v["summary"]:
            key = f"study.{v['target']}.{r['metric']}"
            out[f"{key}.within_pct"] = _round(100.0 * r["within"])
            out[f"{key}.cells"] = r["cells"]
            out[f"{key}.worst_pct"] = _round(100.0 * r["worst_rel"])
            if v["target"] in ("mujoco", "bullet"):
                engines.setdefault(r["metric"], []).append(abs(100.0 * r["worst_rel"]))
    for m, vals in engines.items():
        out[f"study.engines.{m}.abs_worst_pct"] = _round(max(vals))
    return out


def from_contact_fit(fit: dict) -> dict:
    """The models held against the paper's measurements (``paper --fit-contact``)."""
    out: dict = {}
    trees = fit["contact_fit"]
    explained = 0
    for name, tree in trees.items():
        for model, f in tree["fits"].items():
            key = f"fit.{name}.{model}"
            for p, v in f["parameters"].items():
                out[f"{key}.{p}"] = _round(1e3 * v["value"] if p == "contact_duration"
                                           else v["value"])
            for target, v in f["targets"].items():
                if _finite(v["residual"]):
                    out[f"{key}.residual_pct.{target}"] = _round(100.0 * v["residual"])
            out[f"{key}.rms_pct"] = _round(100.0 * f["rms"])
            out[f"{key}.dof"] = f["dof"]
            explained += len(f["explains"])
        out[f"fit.{name}.explained_by_none"] = len(tree["explained_by_none"])
    out["fit.explained"] = explained
    for model in {m for t in trees.values() for m in t["fits"]}:
        for target in {k for t in trees.values() for k in t["measured"]}:
            vals = [out.get(f"fit.{n}.{model}.residual_pct.{target}") for n in trees]
            _put(out, f"fit.{model}.residual_pct.{target}", _span(vals))
        _put(out, f"fit.{model}.rms_pct", _span([out.get(f"fit.{n}.{model}.rms_pct")
                                                 for n in trees]))
    for target in {k for t in trees.values() for k in t["measured"]}:
        vals = [out.get(f"fit.{n}.{m}.residual_pct.{target}") for n, t in trees.items()
                for m in t["fits"]]
        _put(out, f"fit.all.residual_pct.{target}", _span(vals))
        _put(out, f"abs.fit.all.residual_pct.{target}",
             _span([abs(v) for v in vals if _finite(v)]))
    out["fit.targets"] = sum(len(t["measured"]) for t in trees.values())
    out["fit.models"] = len({m for t in trees.values() for m in t["fits"]})
    return out


def at_fitted_contact(fit: dict) -> dict:
    """The 1-DOF soft model against the continuum at the pad the continuum was fitted to on
    each tree (what the 1-DOF assumption costs there): four runs, a second."""
    from treeimpact.analytic.contact.soft import simulate_soft
    from treeimpact.analytic.continuum.beam_impact import simulate_beam
    from treeimpact.analytic.model.scenario import load_scenario

    out: dict = {}
    gaps: dict = {"x_max": {}, "energy_delivered": {}}
    for name, tree in fit["contact_fit"].items():
        params = {k: v["value"] for k, v in tree["fits"]["beam"]["parameters"].items()}
        scen = load_scenario(name)
        soft = simulate_soft(scen, **params).metrics
        beam = simulate_beam(scen, **params).metrics
        for m in gaps:
            gaps[m][name] = 100.0 * (beam[m] / soft[m] - 1.0)
    for m, by_tree in gaps.items():
        for t, v in by_tree.items():
            _put(out, f"fit.at_beam_contact.gap_pct.{m}.{t}", v)
        _put(out, f"fit.at_beam_contact.gap_pct.{m}", _span(by_tree.values()))
    return out


# --------------------------------------------------------------------------- benchmarks


def _bench(name: str) -> dict | None:
    path = BENCHMARKS / f"{name}.json"
    return json.loads(path.read_text()) if path.exists() else None


def from_benchmarks(results: Path | None = None) -> dict:
    """What the benchmarks measured (their results files; timings are quoted from here
    only). Each file's numbers under ``bench.<file>.``; see the benchmark for their meaning."""
    out: dict = {}
    results = BENCHMARKS if results is None else results
    for path in sorted(results.glob("*.json")):
        data = json.loads(path.read_text())
        flat = data.get("numbers")
        if isinstance(flat, dict):
            for k, v in flat.items():
                _put(out, f"bench.{path.stem}.{k}", v)
        load = data.get("load_average") or {}
        if isinstance(load, dict) and load.get("start") and load.get("end"):  # 1-minute
            _put(out, f"bench.{path.stem}.load_average",
                 _span([load["start"][0], load["end"][0]]))
    if (results / "trunks.json").exists():
        out |= from_trunks(json.loads((results / "trunks.json").read_text()))
    return out


def from_trunks(data: dict) -> dict:
    """benchmarks/results/trunks.json (bench_trunks.py): per tree, trunk model and segment
    count, its errors against the continuum (%) and cost at the default step, and each
    step's run (``run<factor>``)."""
    out: dict = {}
    loads = [v for sc in data["scenarios"].values() for v in (
        (sc.get("record") or {}).get("load_average"),
        (sc.get("record") or {}).get("load_average_after")) if v is not None]
    if loads:  # the 1-minute load before and after each tree's runs
        _put(out, "bench.trunks.load_average", _span(loads))
    for tree, sc in data["scenarios"].items():
        for row in sc["rows"]:
            key = f"bench.trunks.{tree}.{row['model']}.{row['segments']}"
            w1, w2 = row["omega_errors"]
            _put(out, f"{key}.static_stiffness_pct", 100.0 * row["static_stiffness_error"])
            _put(out, f"{key}.omega_1_pct", 100.0 * w1)
            _put(out, f"{key}.omega_2_pct", 100.0 * w2)
            for run in row["runs"]:
                if "x_max_error" not in run:
                    continue
                rk = key if run["factor"] == 1 else f"{key}.run{run['factor']:g}"
                _put(out, f"{rk}.x_max_pct", 100.0 * run["x_max_error"])
                _put(out, f"{rk}.energy_delivered_pct", 100.0 * run["energy_delivered_error"])
                _put(out, f"{rk}.s_per_s", run["wall_per_simulated_s"])
    # across the trees: the recommended N = 8 at 16 times the default step, what the step
    # changes there, and the energy delivered from N = 16 on
    rows = [(tree, row) for tree, sc in data["scenarios"].items() for row in sc["rows"]]
    n8 = [row for _, row in rows if row["segments"] == 8]
    at16 = [r for row in n8 for r in row["runs"] if r["factor"] == 16 and "x_max_error" in r]
    _put(out, "bench.trunks.n8.run16.s_per_s", _span(r["wall_per_simulated_s"] for r in at16))
    _put(out, "bench.trunks.n8.run16.dt", _span(r["dt"] for r in at16))
    _put(out, "bench.trunks.n8.step_effect_x_max_pct", max(
        abs(100.0 * (r["x_max_error"] - row["runs"][0]["x_max_error"]))
        for row in n8 for r in row["runs"] if "x_max_error" in r))
    _put(out, "bench.trunks.n16_up.abs_energy_delivered_pct", max(
        abs(100.0 * row["runs"][0]["energy_delivered_error"]) for _, row in rows
        if row["segments"] >= 16))
    return out


# --------------------------------------------------------------------------- the numbers


def numbers() -> dict:
    """Every quotable number: docs/numbers.json and what the checked-in results files give."""
    out = dict(json.loads(NUMBERS.read_text())["numbers"]) if NUMBERS.exists() else {}
    if CONTACT_FIT.exists():
        out |= from_contact_fit(json.loads(CONTACT_FIT.read_text()))
    if IDENTIFY_VALIDATION.exists():
        for k, v in json.loads(IDENTIFY_VALIDATION.read_text())["numbers"].items():
            _put(out, f"identify.{k}", v)
    out |= from_benchmarks()
    return out


def shipped() -> dict:
    """The shipped trees' inputs the pages quote, and the studies' tolerance."""
    from treeimpact.analytic.model.scenario import load_scenario

    from .verdicts import validity_tolerance

    out: dict = {"validity_tolerance_pct": _round(100.0 * validity_tolerance())}
    scens = {t: load_scenario(t) for t in TREES}
    for key, get in (("contact_duration_ms", lambda s: 1e3 * s.contact.duration),
                     ("restitution", lambda s: s.contact.restitution),
                     ("clamp_mass_kg", lambda s: s.trunk.clamp_mass),
                     ("crown_mass_kg", lambda s: s.trunk.crown_mass),
                     ("impactor_mass_kg", lambda s: s.impactor.mass)):
        _per_tree(out, f"shipped.{key}", {t: get(s) for t, s in scens.items()})
    # how much softer the Timoshenko trunk is at the clamp (the scenario's shear modulus)
    from treeimpact.analytic.continuum.beam import beam_static_stiffness

    def softening(trunk, e_over_g=None):
        if e_over_g is not None:
            trunk = replace(trunk, shear_modulus=trunk.youngs_modulus / e_over_g)
        return 100.0 * (1.0 - beam_static_stiffness(trunk, "timoshenko")
                        / beam_static_stiffness(trunk))

    _per_tree(out, "timoshenko.static_softening_pct",
              {t: softening(s.trunk) for t, s in scens.items()})
    _put(out, "timoshenko.static_softening_pct.e_over_g_10_to_20",
         _span([softening(s.trunk, r) for s in scens.values() for r in (10.0, 20.0)]))
    # the code's own limits the pages quote
    from treeimpact.analytic.impact.solver import MAX_CHATTER_IMPACTS

    out["code.max_chatter_impacts"] = MAX_CHATTER_IMPACTS
    import inspect

    from treeimpact.analytic.identify.record_fit import RESOLUTION
    from treeimpact.analytic.records import metrics_from_record

    out["code.identify_resolution"] = RESOLUTION
    from .studies.ident_study import FIT_NOISE

    out["code.report_fit_noise_pct"] = _round(100.0 * FIT_NOISE)
    out["code.persist_factor"] = inspect.signature(metrics_from_record).parameters[
        "persist_factor"].default
    # where the flexibility at the clamp is: the root spring's share, and what shear adds
    # below the clamp (E / G = 13, the default)
    shares, shear = {}, {}
    for t, scen in scens.items():
        tr = scen.trunk
        a = tr.clamp_height
        root = a * a / tr.base_stiffness if math.isfinite(tr.base_stiffness) else 0.0
        shares[t] = 100.0 * root * beam_static_stiffness(tr)
        shear[t] = 100.0 * (a / tr.shear_rigidity) / (a ** 3 / (3.0 * tr.bending_stiffness))
    _per_tree(out, "root.flexibility_share_pct", shares)
    _per_tree(out, "timoshenko.shear_over_bending_pct", shear)
    # the engines' hinged chain against the beam, one segment below the default and at 64
    from treeimpact.analytic.continuum.chain import chain_errors, default_segments

    worst64 = []
    for t, scen in scens.items():
        n = default_segments(scen.trunk)
        for k, v in chain_errors(scen.trunk, n - 1).items():
            out[f"chain.below_default.{k}_pct.{t}"] = _round(100.0 * v)
        worst64 += [abs(v) for v in chain_errors(scen.trunk, 64).values()]
    out["chain.n64.worst"] = _round(max(worst64))
    # the engines' time-step rule and work budget (analytic/contact/timestep.py)
    from treeimpact.analytic.contact import timestep

    rule = inspect.signature(timestep.choose_time_step).parameters
    out["code.timestep.steps_per_collision"] = rule["steps_per_collision"].default
    out["code.timestep.steps_per_period"] = rule["steps_per_period"].default
    from treeimpact.analytic import budget

    out["code.budget.max_steps"] = budget.MAX_STEPS
    out["code.budget.max_gb"] = budget.MAX_BYTES / 1e9
    out["code.budget.max_seconds"] = budget.MAX_SECONDS
    # the sensitivity study's design (compare/sensitivity.py, the presets)
    from .studies.sensitivity import DURATIONS as PADS
    from .studies.sensitivity import INPUTS, LEVELS
    from .validity.study import PRESETS

    out["code.sensitivity.levels"] = LEVELS
    out["code.sensitivity.inputs"] = len(INPUTS)
    out["code.sensitivity.pads"] = len(PADS)
    out["code.sensitivity.pad_range_ms"] = _round([1e3 * PADS[0], 1e3 * PADS[-1]])
    for name, (low, high, unit, *_) in INPUTS.items():
        if unit == "log10 s":
            low, high = 1e3 * 10.0 ** low, 1e3 * 10.0 ** high
        out[f"code.sensitivity.input.{name}"] = _round([low, high])
    for name, preset in PRESETS.items():
        out[f"code.preset.{name}.trajectories"] = preset.sensitivity
        out[f"code.preset.{name}.points"] = preset.sensitivity * (len(INPUTS) + 1)
    return out


def beam_studies() -> dict:
    """The continuum rung's convergence in elements and what Timoshenko's theory changes on
    the shipped trees (docs/beam-impact.md; about 2 s)."""
    from treeimpact.analytic.continuum.beam import beam_natural_frequencies
    from treeimpact.analytic.continuum.beam_impact import simulate_beam
    from treeimpact.analytic.model.scenario import load_scenario

    out: dict = {}
    for t in TREES:
        scen = load_scenario(t)
        runs = {n: simulate_beam(scen, elements=n).metrics for n in (12, 24, 40, 48)}
        for n, m in runs.items():
            out[f"beam.elements{n}.energy_delivered.{t}"] = _round(m["energy_delivered"])
            out[f"beam.elements{n}.x_max_mm.{t}"] = _round(1e3 * m["x_max"])
            if n != 48:
                for k in ("energy_delivered", "x_max"):
                    out[f"beam.elements{n}.vs48_pct.{k}.{t}"] = _round(
                        100.0 * abs(m[k] / runs[48][k] - 1.0))
        w_eb = beam_natural_frequencies(scen.trunk, 2)
        if t == "central-leader":  # rotary inertia alone: the Rayleigh beam (G = inf)
            rayleigh = beam_natural_frequencies(replace(scen.trunk, shear_modulus=math.inf),
                                                2, "timoshenko")
            for i in (0, 1):
                out[f"rayleigh.omega_{i + 1}_pct.{t}"] = _round(
                    100.0 * abs(rayleigh[i] / w_eb[i] - 1.0))
        for e_over_g in (10.0, 13.0, 20.0):
            trunk = replace(scen.trunk, shear_modulus=scen.trunk.youngs_modulus / e_over_g)
            m = simulate_beam(replace(scen, trunk=trunk), beam_theory="timoshenko").metrics
            w = beam_natural_frequencies(trunk, 2, "timoshenko")
            key = f"timoshenko.e_over_g{e_over_g:g}"
            for k in ("x_max", "energy_delivered"):
                out[f"{key}.{k}_pct.{t}"] = _round(100.0 * (m[k] / runs[12][k] - 1.0))
            for i in (0, 1):
                out[f"{key}.omega_{i + 1}_pct.{t}"] = _round(100.0 * (w[i] / w_eb[i] - 1.0))
    for n in (12, 24, 40):
        for k in ("energy_delivered", "x_max"):
            _put(out, f"beam.elements{n}.vs48_pct.{k}", _span(
                [out[f"beam.elements{n}.vs48_pct.{k}.{t}"] for t in TREES]))
    _put(out, "timoshenko.omega_2_drop_pct", _span(
        [-out[f"timoshenko.e_over_g{r:g}.omega_2_pct.{t}"] for t in TREES
         for r in (10.0, 13.0, 20.0)]))
    return out


#: The collisions of docs/contact-settings.md's table: (m1, m2 (inf: fixed), e, duration,
#: dt), SI.
CONTACT_CASES = ((132.4, 4.0, 0.5, 2e-3, 4e-5), (132.4, 110.0, 0.1, 5e-4, 1e-5),
                 (1.0, math.inf, 0.8, 1e-3, 1e-5), (132.4, 4.0, 0.5, 2e-3, 2e-4),
                 (1.0, math.inf, 0.05, 1e-3, 1e-4))


def contact_command() -> dict:
    """``treeimpact contact`` on :data:`CONTACT_CASES`: what each engine achieves with the
    corrected settings and with the naive formula (about 1 s)."""
    from .contact_settings import contact_settings

    out: dict = {}
    errs: dict = {"mujoco": [], "bullet": []}
    naive: dict = {"mujoco": [], "bullet": []}
    durations: dict = {}
    for i, (m1, m2, e, duration, dt) in enumerate(CONTACT_CASES):
        res = contact_settings(mass=m1, other_mass=m2, restitution=e,
                               touch_duration=duration, dt=dt)
        key = f"contact_cmd.{i}"
        law = res["target"]
        steps = round(law["touch_duration"] / dt)
        out[f"{key}.steps"] = steps
        out[f"{key}.damping_ratio"] = _round(law["damping_ratio"])
        for engine in ("mujoco", "bullet"):
            ach = res[engine]["achieved"]
            ach = ach if "restitution" in ach else ach["solref"]
            out[f"{key}.{engine}.e"] = _round(ach["restitution"])
            out[f"{key}.{engine}.duration_pct"] = _round(
                100.0 * (ach["touch_duration"] / law["touch_duration"] - 1.0))
            out[f"{key}.{engine}.naive_e"] = _round(res[engine]["naive"]["restitution"])
            out[f"{key}.{engine}.naive_miss"] = _round(
                res[engine]["naive"]["restitution"] - e)
            errs[engine] += [abs(a["restitution"] - e) for a in (
                [res[engine]["achieved"]] if "restitution" in res[engine]["achieved"]
                else res[engine]["achieved"].values())]
            naive[engine].append(abs(res[engine]["naive"]["restitution"] - e))
            durations.setdefault(steps, []).append(abs(out[f"{key}.{engine}.duration_pct"]))
        timeconst = res["mujoco"]["achieved"].get("solref_timeconst")
        if timeconst:
            out[f"{key}.mujoco.timeconst_e"] = _round(timeconst["restitution"])
    for engine in errs:
        out[f"contact_cmd.{engine}.e_error_max"] = _round(max(errs[engine]))
        _put(out, f"contact_cmd.{engine}.naive_miss", _span(naive[engine]))
    for steps, d in durations.items():
        out[f"contact_cmd.duration_pct_max.steps{steps}"] = _round(max(d))
    _put(out, "contact_cmd.steps", _span(out[f"contact_cmd.{i}.steps"]
                                         for i in range(len(CONTACT_CASES))))
    return out


#: docs/contact-settings.md's example at MuJoCo's default step: (m1, m2, e, touch duration,
#: dt), SI; the step Bullet cannot hold for it.
DEFAULT_STEP_CASE = (1.0, 1.0, 0.75, 5e-3, 2e-3)
BULLET_REFUSED_DT = 1e-3


def contact_default_step() -> dict:
    """``treeimpact contact`` at MuJoCo's default 2 ms step (:data:`DEFAULT_STEP_CASE`): the
    touch's steps, the duration's error, e of the same setting at dt/2 and 2 dt, and the
    largest step Bullet takes for it (about 0.1 s)."""
    from .contact_settings import contact_settings

    m1, m2, e, touch, dt = DEFAULT_STEP_CASE
    res = contact_settings(mass=m1, other_mass=m2, restitution=e, touch_duration=touch, dt=dt,
                           engines=("mujoco",))
    mj = res["mujoco"]
    bl = contact_settings(mass=m1, other_mass=m2, restitution=e, touch_duration=touch,
                          dt=BULLET_REFUSED_DT, engines=("bullet",))["bullet"]
    key = "contact_cmd.default_step"
    return {f"{key}.steps_per_touch": touch / dt,
            f"{key}.e": _round(mj["achieved"]["solref"]["restitution"]),
            f"{key}.duration_pct": _round(100.0 * (
                mj["achieved"]["solref"]["touch_duration"] / touch - 1.0)),
            f"{key}.half_dt_e": _round(mj["at_half_dt"]["solref"]["restitution"]),
            f"{key}.double_dt_e": _round(mj["at_double_dt"]["solref"]["restitution"]),
            "contact_cmd.bullet_largest_dt": _round(bl["largest_dt"])}


#: Seeds of :func:`procedure_on_noisy_records` (issue 34: the README quoted a median from
#: one kind of record that the README's own commands do not give).
PROCEDURE_SEEDS = 100


def procedure_on_noisy_records() -> dict:
    """The paper's procedure (eqs 39-48, its ``paper`` reading) on seeded records of the
    central-leader model at 5 kHz with 1 % noise (compare.recording, as `treeimpact simulate
    --record` writes them), with 20 ms of rest before the impact (the README's commands)
    and with 10 ms (the cut docs/identification.md's table uses): the median and the range
    over :data:`PROCEDURE_SEEDS` seeds of its M_T error, % (a few seconds)."""
    import numpy as np

    from treeimpact.analytic.identify.procedure import PendulumTest, identify_from_record
    from treeimpact.analytic.model.scenario import load_scenario

    from .backends import get_backend
    from .recording import REST, sample

    tree = load_scenario("central-leader")
    result = get_backend("analytic").simulate(tree)
    pend, trunk = tree.impactor, tree.trunk
    test = PendulumTest(impactor_mass=pend.mass, equivalent_length=pend.equivalent_length,
                        release_angle=pend.release_angle_rad, clamp_height=trunk.clamp_height,
                        diameter=trunk.diameter, gravity=pend.gravity)
    out = {}
    for rest in (0.02, 0.01):
        errors = []
        for seed in range(PROCEDURE_SEEDS):
            t, x = sample(result, 5000.0, 0.01, seed)
            keep = t >= REST - rest - 1e-12
            with np.errstate(all="ignore"):
                ident, _ = identify_from_record(t[keep] - t[keep][0], x[keep], test)
            errors.append(100.0 * (ident.M_T / result.model["M_T"] - 1.0))
        key = f"ident.procedure.rest{round(1e3 * rest)}ms.M_T_pct"
        out[f"{key}.median"] = _round(float(np.median(errors)))
        _put(out, f"{key}.range", _round(_span(errors)))
    return out


def cheap_numbers() -> dict:
    """The part of docs/numbers.json a test reruns (a few seconds)."""
    out = (from_view(view_from_ladders(cheap_ladders())) | shipped() | beam_studies()
           | contact_command() | contact_default_step() | procedure_on_noisy_records()
           | small_e_now())
    if CONTACT_FIT.exists():
        out |= at_fitted_contact(json.loads(CONTACT_FIT.read_text()))
    return out


def write_numbers(report_dir: Path, path: Path = NUMBERS) -> list[str]:
    """docs/numbers.json from a report directory and the cheap part rerun now; returns the
    keys where the two disagree beyond :data:`RECOMPUTE_REL` (the report is from other
    code than this checkout: rerun ``make report``)."""
    from .provenance import code_version, environment

    report = json.loads((Path(report_dir) / "report.json").read_text())
    out = (from_view(view_from_report(report)) | from_sensitivity(report)
           | from_small_e(report["answer"]["small_e"]))
    study = Path(report_dir) / "study" / "study.json"
    if study.exists():
        out |= from_study(json.loads(study.read_text()))
    cheap = cheap_numbers()
    drift = [k for k, v in cheap.items() if k in out and not _close(out[k], v, RECOMPUTE_REL)]
    out |= cheap
    out = {k: v for k, v in out.items() if k in used_keys(out) or k.startswith(KEEP)}
    data = {"about": "The numbers README.md and docs/*.md quote (compare/docs.py): derived from "
                     "a report by `python -m treeimpact.compare.docs numbers REPORT_DIR`, its "
                     "cheap part rerun; display units as the keys say (DISPLAY in "
                     "compare/docs.py for value.*); [a, b] is a range (min, max).",
            "report": {"generated": report.get("generated"),
                       "provenance": report.get("provenance", {}).get("code")},
            "code": code_version(), "environment": environment(),
            "figures": copy_figures(Path(report_dir), report),
            "numbers": dict(sorted(out.items()))}
    path.write_text(json.dumps(data, indent=1) + "\n")
    return drift


#: The report's figures the pages show, copied with the numbers: page path -> report path.
FIGURES = {"docs/img/contact-scan.png": "figures/contact-scan.png",
           "docs/img/small-e.png": "figures/small-e.png"}


def copy_figures(report_dir: Path, report: dict) -> dict:
    """Copy :data:`FIGURES` from the report directory into docs/ (the README shows the
    contact scan); what was copied, with each copy's SHA-1 and the report it came from
    (tests/test_doc_numbers.py checks the copies are these)."""
    import hashlib
    import shutil

    out = {}
    for page_path, report_path in FIGURES.items():
        source = Path(report_dir) / report_path
        if not source.exists():
            continue
        shutil.copyfile(source, ROOT / page_path)
        out[page_path] = {"from": report_path, "report_generated": report.get("generated"),
                          "sha1": hashlib.sha1((ROOT / page_path).read_bytes()).hexdigest()}
    return out


def _close(a, b, rel: float) -> bool:
    if isinstance(a, list) or isinstance(b, list):
        return (isinstance(a, list) and isinstance(b, list) and len(a) == len(b)
                and all(_close(x, y, rel) for x, y in zip(a, b)))
    return abs(a - b) <= rel * max(abs(a), abs(b)) + 1e-12


# --------------------------------------------------------------------------- the pages

PAGES = (ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")))
_NUM = r"[-+]?(?:\d+(?:\.\d+)?|\.\d+)(?:[eE][-+]?\d+)?"
_SEP = r"\s*(?:,\s*and|,|\band\b|/|\.\.|\bto\b|-)\s*"
_QUOTED = re.compile(rf"(?<![\w.\-+])(?P<nums>{_NUM}(?:{_SEP}{_NUM})*)"
                     r"(?P<unit>\s*(?:%|[A-Za-z][\w/^*\-]*)?)\s*$")
MARK = re.compile(r"<!-- check(?P<mode>-max|-min)?: (?P<key>[\w.\-/]+)"
                  r"(?: ~(?P<rel>[\d.]+)%)? -->")
BLOCK = re.compile(r"<!-- BEGIN generated: (?P<name>[\w.\-]+) -->\n(?P<body>.*?)"
                   r"<!-- END generated: (?P=name) -->", re.S)


def _tokens(text: str) -> list[str]:
    """The numbers of a quoted list, in order (a separator's '-' is not a sign)."""
    num, sep = re.compile(_NUM), re.compile(_SEP)
    out, pos = [], 0
    while True:
        m = num.match(text, pos)
        out.append(m.group())
        s = sep.match(text, m.end())
        if s is None or not num.match(text, s.end()):
            return out
        pos = s.end()


def _half_unit(token: str) -> float:
    """Half a unit of the last digit a number is printed to ('8.5' -> 0.05, '1.2e-5' ->
    5e-7, '130' -> 0.5)."""
    mant, _, exp = token.lower().lstrip("+-").partition("e")
    decimals = len(mant.split(".")[1]) if "." in mant else 0
    return 0.5 * 10.0 ** (int(exp or 0) - decimals)


def _blank_code(text: str) -> str:
    """The text with its code blocks and spans blanked (a mark shown as an example is no
    mark), lines kept."""
    text = re.sub(r"```.*?```", lambda m: re.sub(r"[^\n]", " ", m.group()), text, flags=re.S)
    return re.sub(r"`[^`\n]*`", lambda m: " " * len(m.group()), text)


def quoted(page_text: str) -> list[dict]:
    """Every marked number of a page: {key, mode, rel, text, tokens, line}."""
    page_text = _blank_code(page_text)
    out = []
    for m in MARK.finditer(page_text):
        before = page_text[max(0, m.start() - 200):m.start()]
        q = _QUOTED.search(before)
        line = page_text.count("\n", 0, m.start()) + 1
        out.append({"key": m["key"], "mode": m["mode"] or "", "rel": m["rel"], "line": line,
                    "text": q["nums"] if q else None,
                    "tokens": _tokens(q["nums"]) if q else []})
    return out


def _agrees(token: str, value: float, mode: str, rel: str | None) -> bool:
    q = float(token)
    tol = float(rel) / 100.0 * abs(value) if rel else _half_unit(token) * (1 + 1e-9)
    if mode == "-max":
        return value <= q + tol
    if mode == "-min":
        return value >= q - tol
    return abs(q - value) <= tol


def check_marks(pages=PAGES, values: dict | None = None) -> list[str]:
    """One line per quoted number that is not its key's value (or has no number, or names
    no key)."""
    values = numbers() if values is None else values
    problems = []
    for page in pages:
        for q in quoted(Path(page).read_text()):
            where = f"{Path(page).name}:{q['line']}"
            if q["key"] not in values:
                problems.append(f"{where}: no number named {q['key']!r} in the sources")
                continue
            if not q["tokens"]:
                problems.append(f"{where}: no number just before the mark of {q['key']!r}")
                continue
            value = values[q["key"]]
            value = value if isinstance(value, list) else [value]
            if len(q["tokens"]) == 1 and len(value) == 2:
                # one number for a range: a bound of it, or the value of all of it
                value = {"-max": [max(value)], "-min": [min(value)]}.get(q["mode"], value)
                if len(value) == 2 and all(_agrees(q["tokens"][0], v, "", q["rel"])
                                           for v in value):
                    value = value[:1]
            if len(value) != len(q["tokens"]):
                problems.append(f"{where}: {q['text']!r} quotes {len(q['tokens'])} number(s), "
                                f"{q['key']} has {len(value)}: {value}")
                continue
            bad = [(t, v) for t, v in zip(q["tokens"], value)
                   if not _agrees(t, v, q["mode"], q["rel"])]
            if bad:
                problems.append(f"{where}: {q['text']!r} but {q['key']} = "
                                f"{_show(values[q['key']])}")
    return problems


def check_now(fresh: dict, pages=PAGES) -> list[str]:
    """:func:`check_marks` and :func:`check_blocks` against the code now: the sources with
    ``fresh`` (what :func:`cheap_numbers` gives on this machine) in place of the values
    they store, so each number is compared at the digits its page prints (or the ``~%`` it
    states). A CPU whose BLAS moves a value in its last bits passes; a printed digit that
    drifted fails."""
    values = numbers() | fresh
    return check_marks(pages, values) + check_blocks(pages, values)


def _show(v) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"
    return f"{v:.6g}"


# --------------------------------------------------------------------------- generated blocks


def _fmt(v: float, digits: int) -> str:
    return f"{v:.{digits}f}"


def _signed(v: float, digits: int) -> str:
    return f"{v:+.{digits}f}"


def _thousands(v: float) -> str:
    return f"{v:,.0f}".replace(",", " ")


def whole_event_table(n: dict) -> str:
    """docs/whole-event-metrics.md: the 1-DOF model -> the continuum on the shipped trees, as
    the report's answer table: the paper's (Newton) model, the soft one for the force and the
    acceleration (Newton's impulses have none)."""
    rows = ["| tree | energy delivered (J) | contact loss (J) | crown peak (mm) | crown "
            "acceleration (m/s^2) | contact force (kN) |", "|---|---|---|---|---|---|"]
    for t in TREES:
        cells = []
        for m, fmt in (("energy_delivered", lambda v: f"{v:.0f}"),
                       ("contact_dissipation", lambda v: f"{v:.0f}"),
                       ("crown_peak", lambda v: f"{v:.1f}"),
                       ("crown_peak_acceleration", lambda v: _thousands(round(v, -1))),
                       ("peak_force", lambda v: f"{v:.0f}")):
            one_dof = "contact" if m in ("crown_peak_acceleration", "peak_force") else "newton"
            a, b = n[f"value.{one_dof}.{m}.{t}"], n[f"value.beam.{m}.{t}"]
            cells.append(f"{fmt(a)} -> {fmt(b)} ({100 * (b / a - 1):+.0f} %)")
        rows.append(f"| {t} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def mechanism_table(n: dict) -> str:
    """docs/whole-event-metrics.md: the 1-DOF model with the continuum's impact loss."""
    rows = ["| tree | e* | energy delivered gap at e -> at e* | x_max gap at e -> at e* | "
            "crown peak gap at e -> at e* |", "|---|---|---|---|---|"]
    for t in TREES:
        cells = [f"{n[f'mechanism.e_star.{t}']:.3f}"]
        for m in ("energy_delivered", "x_max", "crown_peak"):
            a, b = n[f"mechanism.gap_pct.{m}.{t}"], n[f"mechanism.matched_gap_pct.{m}.{t}"]
            cells.append(f"{a:+.1f} % -> {b:+.1f} %")
        rows.append(f"| {t} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


_TARGET_ORDER = ("V", "x0", "T0", "x_max", "tau", "theta_b")
_PARAM = {"contact_duration": ("pad", "ms", 3), "restitution": ("e", "", 3),
          "clamp_mass": ("clamp", "kg", 3)}


def contact_fit_table(n: dict) -> str:
    """docs/contact-law.md: every model against every measured number (the fit file)."""
    fit = json.loads(CONTACT_FIT.read_text())["contact_fit"]
    head = "| tree | model | fitted | dof | " + " | ".join(_TARGET_ORDER) + " | rms |"
    rows = [head, "|---|---|---|---:|" + "---:|" * len(_TARGET_ORDER) + "---:|"]
    for t in ("open-center", "central-leader"):
        for model, f in fit[t]["fits"].items():
            params = ", ".join(
                f"{_PARAM[p][0]} {n[f'fit.{t}.{model}.{p}']:.{_PARAM[p][2]}g}"
                f"{' ' + _PARAM[p][1] if _PARAM[p][1] else ''}"
                f"{' (bound)' if v['on_bound'] else ''}" for p, v in f["parameters"].items())
            cells = []
            for k in _TARGET_ORDER:
                r = n.get(f"fit.{t}.{model}.residual_pct.{k}")
                cells.append("n/a" if r is None else f"{r:+.0f} %"
                             + (" (explained)" if f["targets"][k]["explained"] else ""))
            rows.append(f"| {t} | {model} | {params} | {f['dof']} | " + " | ".join(cells)
                        + f" | {n[f'fit.{t}.{model}.rms_pct']:.0f} % |")
    return "\n".join(rows) + "\n"


def _trunks() -> dict:
    return json.loads((BENCHMARKS / "trunks.json").read_text())


def trunks_cheapest_table(n: dict) -> str:
    """docs/engines.md: the cheapest MuJoCo run within 1 % of the continuum on x_max, per
    tree and trunk (benchmarks/results/trunks.json, bench_trunks.py)."""
    rows = ["| tree | use | N | dt (s) | x default | x_max | energy delivered "
            "| s per simulated s |", "|---|---|---|---|---|---|---|---|"]
    for tree, sc in _trunks()["scenarios"].items():
        for c in sc["cheapest"]:
            row = next(r for r in sc["rows"]
                       if r["model"] == c["model"] and r["segments"] == c["segments"])
            factor = next(r["factor"] for r in row["runs"] if r["dt"] == c["dt"])
            rows.append(f"| {tree} | `--trunk {c['model']}` | {c['segments']} | {c['dt']:.2g} "
                        f"| {factor:g} | {c['x_max_error']:+.2%} | "
                        f"{c['energy_delivered_error']:+.2%} | "
                        f"{c['wall_per_simulated_s']:.2g} |")
    return "\n".join(rows) + "\n"


def trunks_segments_table(n: dict) -> str:
    """docs/engines.md: central-leader's MuJoCo trunks per segment count at the default step
    (benchmarks/results/trunks.json; ``bench_trunks.py --table`` prints every tree)."""
    return "\n".join(trunk_rows_table(_trunks()["scenarios"]["central-leader"]["rows"])) + "\n"


def trunk_rows_table(trunk_rows: list) -> list[str]:
    """The markdown lines of one tree's rows of trunks.json (bench_trunks.py): each (model,
    N) at the runner's default step, errors against the continuum, steps and cost."""
    rows = ["| trunk | N | static K at a | omega_1 | omega_2 | x_max | energy delivered "
            "| default dt (s) | largest stable dt, trunk (s) | runner's limit (s) "
            "| s per simulated s |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in trunk_rows:
        run = row["runs"][0]
        w1, w2 = row["omega_errors"]
        rows.append(
            f"| {row['model']} | {row['segments']} | {row['static_stiffness_error']:+.2%} "
            f"| {w1:+.2%} | {w2:+.2%} | {run['x_max_error']:+.2%} "
            f"| {run['energy_delivered_error']:+.2%} | {row['default_dt']:.2g} "
            f"| {row['trunk_stable_dt']:.2g} | {row['runner_limit']:.2g} "
            f"| {run['wall_per_simulated_s']:.3g} |")
    return rows


def timoshenko_table(n: dict) -> str:
    """docs/beam-impact.md: Timoshenko against Euler-Bernoulli on the shipped trees."""
    rows = ["| tree | E / G | x_max | energy_delivered | omega_1 | omega_2 |",
            "|---|---|---|---|---|---|"]
    for t in TREES:
        cells = []
        for k, d in (("x_max", 2), ("energy_delivered", 2), ("omega_1", 2), ("omega_2", 1)):
            vals = [n[f"timoshenko.e_over_g{r}.{k}_pct.{t}"] for r in (10, 13, 20)]
            cells.append(" / ".join(_signed(v, d) for v in vals) + " %")
        rows.append(f"| {t} | 10 / 13 / 20 | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def beam_cost_table(n: dict) -> str:
    """docs/beam-impact.md: bench_beam's medians (benchmarks/results/beam-12.json, -48)."""
    rows = ["| elements | `exact-full` (original) | `exact` | ratio | x_max, energy_delivered |",
            "|---|---|---|---|---|"]
    for e in (12, 48):
        b = f"bench.beam-{e}"
        full, exact, ratio = n[f"{b}.exact_full_ms"], n[f"{b}.exact_ms"], n[f"{b}.ratio"]
        dx, de = n[f"{b}.x_max_rel_diff"][1], n[f"{b}.energy_delivered_rel_diff"][1]
        rows.append(f"| {e} | {full[0]:.0f}-{full[1]:.0f} ms | {exact[0]:.1f}-{exact[1]:.1f} ms "
                    f"| {ratio[0]:.1f}-{ratio[1]:.1f} | the same to {dx:.0e}, {de:.0e} |")
    return "\n".join(rows) + "\n"


def solver_cost_table(n: dict) -> str:
    """docs/solver.md: bench_solver's medians (benchmarks/results/solver.json)."""
    rows = ["| scenario | simulate | + reading the trajectory | quadrature integrals, "
            "trajectory up front | ratio |", "|---|---|---|---|---|"]
    for t in TREES:
        b = "bench.solver"
        rows.append(f"| {t} | {n[f'{b}.simulate_ms.{t}']:.3f} | "
                    f"{n[f'{b}.with_trajectory_ms.{t}']:.3f} | "
                    f"{n[f'{b}.quadrature_ms.{t}']:.3f} | {n[f'{b}.ratio.{t}']:.1f} |")
    return "\n".join(rows) + "\n"


def _option_values(option) -> str:
    if option.choices:
        return ", ".join(f"`{c}`" for c in option.choices)
    kind = "integer" if option.kind is int else "number"
    low = "-inf" if option.low is None else f"{option.low:g}"
    high = "inf" if option.high is None else f"{option.high:g}"
    unit = f" {option.unit}" if option.unit not in ("", "1") else ""
    return f"{kind} in {'(' if option.low_open else '['}{low}, {high}]{unit}"


def preset_slice_table(n: dict) -> str:
    """docs/sweeps.md: a chain run's wall time per engine and segment count on the full
    preset's slice (benchmarks/results/presets.json)."""
    counts = (1, 2, 4, 8, 16, 32)
    rows = ["| segments | " + " | ".join(str(c) for c in counts) + " |",
            "|---|" + "---|" * len(counts)]
    for engine, label in (("mujoco", "MuJoCo"), ("bullet", "Bullet")):
        cells = []
        for c in counts:
            lo, hi = n[f"bench.presets.run_s.{engine}.{c}"]
            cells.append(f"{lo:.2g}-{hi:.2g} s")
        rows.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def contact_settings_table(n: dict) -> str:
    """docs/contact-settings.md: ``treeimpact contact`` on :data:`CONTACT_CASES`."""
    rows = ["| m1, m2 (kg) | target e, duration | dt (steps) | MuJoCo e, duration | MuJoCo "
            "naive e | Bullet e, duration | Bullet naive e |", "|---|---|---|---|---|---|---|"]
    for i, (m1, m2, e, duration, dt) in enumerate(CONTACT_CASES):
        k = f"contact_cmd.{i}"
        other = "fixed" if math.isinf(m2) else f"{m2:g}"
        mj = (f"{n[f'{k}.mujoco.e']:.6f}, {n[f'{k}.mujoco.duration_pct']:+.2f}% (timeconst "
              f"{n[f'{k}.mujoco.timeconst_e']:.6f})")
        bl = f"{n[f'{k}.bullet.e']:.6f}, {n[f'{k}.bullet.duration_pct']:+.2f}%"
        rows.append(f"| {m1:g}, {other} | {e:g}, {1e3 * duration:g} ms | {dt:g} s "
                    f"({n[f'{k}.steps']}) | {mj} | {n[f'{k}.mujoco.naive_e']:.4f} "
                    f"({n[f'{k}.mujoco.naive_miss']:+.4f}) | {bl} | "
                    f"{n[f'{k}.bullet.naive_e']:.4f} ({n[f'{k}.bullet.naive_miss']:+.4f}) |")
    return "\n".join(rows) + "\n"


def _backend_option_variants() -> dict:
    """option name -> [(Option, [backends])]: one entry per distinct definition (Bullet's
    --trunk takes fewer words than MuJoCo's)."""
    from treeimpact.analytic.errors import ParameterError

    from .backends import BACKENDS

    out: dict = {}
    for name, backend in BACKENDS.items():
        try:
            table = backend.options()
        except ParameterError:  # a backend that is not installed
            continue
        for key, option in table.items():
            variants = out.setdefault(key, [])
            for known, takers in variants:
                if (known.kind, known.low, known.high, known.low_open, known.unit) == (
                        option.kind, option.low, option.high, option.low_open, option.unit):
                    takers.append(name)
                    break
            else:
                variants.append((option, [name]))
    return out


def options_table(names=None) -> str:
    """The flags the backends' OPTIONS give ``simulate`` (or ``modes``: ``names``)."""
    rows = ["| option | values | backends | what |", "|---|---|---|---|"]
    for key, variants in sorted(_backend_option_variants().items()):
        for option, takers in variants:
            if not option.cli or (names is not None and key not in names):
                continue
            rows.append(f"| `--{key.replace('_', '-')}` | {_option_values(option)} | "
                        f"{', '.join(takers)} | {option.help.replace('%%', '%')} |")
    return "\n".join(rows) + "\n"


def simulate_options(n: dict) -> str:
    """docs/cli.md: ``treeimpact simulate``'s backend options."""
    return options_table()


def modes_options(n: dict) -> str:
    """docs/cli.md: ``treeimpact modes``'s backend options."""
    from .commands.modes import MODES_OPTIONS

    return options_table(MODES_OPTIONS)


def sweep_grid_names(n: dict) -> str:
    """docs/cli.md: the names a ``--grid`` axis may take besides dotted scenario fields."""
    from .sweep.grid import ALIASES, DERIVED_RATIOS, RECORD_FIELDS

    rows = ["| NAME | what |", "|---|---|"]
    for name, target in sorted(ALIASES.items()):
        rows.append(f"| `{name}` | the scenario's `{target}` |")
    for name, (_, meaning) in DERIVED_RATIOS.items():
        rows.append(f"| `{name}` | {meaning} |")
    for key, variants in sorted(_backend_option_variants().items()):
        for option, takers in variants:
            if option.cli and key not in ALIASES:
                extra = " (1: the engine's SDOF trunk)" if key == "segments" else ""
                rows.append(f"| `{key}` | the option `--{key.replace('_', '-')}` of "
                            f"{', '.join(takers)}: {_option_values(option)}{extra} |")
    for name, (_, _, _, unit) in RECORD_FIELDS.items():
        unit = f" ({unit})" if unit not in ("", "1") else ""
        rows.append(f"| `record.{name}` | the sampling of a record{unit}: only in a sweep "
                    "with an analysis (the identification validation) |")
    return "\n".join(rows) + "\n"


#: The generated blocks: name -> function of the numbers giving the block's text.
GENERATED = {"whole-event-table": whole_event_table, "mechanism-table": mechanism_table,
             "contact-fit-table": contact_fit_table, "timoshenko-table": timoshenko_table,
             "beam-cost-table": beam_cost_table, "solver-cost-table": solver_cost_table,
             "trunks-cheapest-table": trunks_cheapest_table,
             "trunks-segments-table": trunks_segments_table,
             "simulate-options": simulate_options, "modes-options": modes_options,
             "sweep-grid-names": sweep_grid_names,
             "contact-settings-table": contact_settings_table,
             "preset-slice-table": preset_slice_table}


def _split(text: str) -> tuple[list[str], list[str]]:
    """(the words between the numbers, the numbers) of a text."""
    parts = re.split(rf"(?<![\w.])({_NUM})(?![\w.])", text)
    return parts[0::2], parts[1::2]


def check_blocks(pages=PAGES, values: dict | None = None) -> list[str]:
    """One line per generated block whose text differs from what its sources give now:
    numbers compared as floats at the digits printed, the rest word for word."""
    values = numbers() if values is None else values
    problems = []
    for page in pages:
        for m in BLOCK.finditer(Path(page).read_text()):
            where = f"{Path(page).name}: block {m['name']}"
            if m["name"] not in GENERATED:
                problems.append(f"{where}: no generator of that name")
                continue
            try:
                want = GENERATED[m["name"]](values)
            except (KeyError, OSError) as exc:
                problems.append(f"{where}: its source lacks {exc}")
                continue
            words, nums = _split(m["body"])
            want_words, want_nums = _split(want)
            if words != want_words or len(nums) != len(want_nums):
                problems.append(f"{where}: the text differs from the generated one (run "
                                "python -m treeimpact.compare.docs write)")
                continue
            bad = [(a, b) for a, b in zip(nums, want_nums)
                   if abs(float(a) - float(b)) > _half_unit(a) * (1 + 1e-9)]
            if bad:
                problems.append(f"{where}: numbers differ (page, source): {bad[:5]}")
    return problems


def write_blocks(pages=PAGES, values: dict | None = None) -> list[str]:
    """Rewrite every generated block from its sources; returns the pages changed."""
    values = numbers() if values is None else values
    changed = []
    for page in pages:
        text = Path(page).read_text()
        new = BLOCK.sub(lambda m: f"<!-- BEGIN generated: {m['name']} -->\n"
                        f"{GENERATED[m['name']](values)}<!-- END generated: {m['name']} -->",
                        text)
        if new != text:
            Path(page).write_text(new)
            changed.append(Path(page).name)
    return changed


#: Keys kept in docs/numbers.json although no page quotes them (tests read them).
KEEP = ("scan", "checks.")


class _Tracking(dict):
    """A dict that remembers which keys were read."""

    def __init__(self, *args):
        super().__init__(*args)
        self.read: set = set()

    def __getitem__(self, key):
        self.read.add(key)
        return super().__getitem__(key)

    def get(self, key, default=None):
        self.read.add(key)
        return super().get(key, default)


def used_keys(values: dict, pages=PAGES) -> set:
    """The keys the pages quote: their marks' and what their generated blocks read."""
    used = {q["key"] for page in pages for q in quoted(Path(page).read_text())}
    tracking = _Tracking(values | from_benchmarks()
                         | (from_contact_fit(json.loads(CONTACT_FIT.read_text()))
                            if CONTACT_FIT.exists() else {}))
    for page in pages:
        for m in BLOCK.finditer(Path(page).read_text()):
            if m["name"] in GENERATED:
                try:
                    GENERATED[m["name"]](tracking)
                except (KeyError, OSError):
                    pass
    return used | tracking.read



# --------------------------------------------------------------------------- command


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m treeimpact.compare.docs",
                                description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    sn = sub.add_parser("numbers", help="write docs/numbers.json from a report directory "
                                        "(make report) and the cheap part rerun now")
    sn.add_argument("report_dir", help="the directory of report.json (make report's OUT)")
    sub.add_parser("write", help="rewrite the generated blocks of the pages")
    sub.add_parser("check", help="list every quoted number and block that drifted")
    args = p.parse_args(argv)
    if args.command == "numbers":
        drift = write_numbers(Path(args.report_dir))
        print(f"wrote {NUMBERS.relative_to(ROOT)}")
        for k in drift:
            print(f"  the report and this checkout disagree on {k}", file=sys.stderr)
        return 1 if drift else 0
    if args.command == "write":
        for name in write_blocks():
            print(f"rewrote {name}")
        return 0
    problems = check_marks() + check_blocks()
    for line in problems:
        print(line)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
