"""The numbers of a report: one view of what a report's JSON (``make report``) or ladders run
now say (:func:`view_from_report`, :func:`view_from_ladders`), so that both are derived by
the same code (:func:`from_view`), and the report's small-e answer, sensitivity ranges and
study summaries. Display units as the keys say (:data:`.base.DISPLAY` for ``value.*``)."""

from __future__ import annotations

import math

from treeimpact.compare.runs.cache import OK

from .base import DISPLAY, TREES, finite, per_tree, put, rounded, span

#: The truth's quantities the pages quote (the scenario's own 1-DOF model).
TRUTH_KEYS = ("M_T", "K_T", "b", "omega_n", "pair_damping_ratio")


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
            if r["status"] != OK:
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
    """The view of ladders run now (:func:`compare.tree.ladder.build_ladder`), with the report's
    own answer and mechanism functions."""
    from types import SimpleNamespace

    from treeimpact.compare.report.answer import one_dof_answer
    from treeimpact.compare.runs.verdicts import relative_step
    from treeimpact.compare.tree.mechanism import matched_loss_evidence

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
    from treeimpact.compare.tree.ladder import build_ladder

    return [build_ladder(t, engines=()) for t in TREES]


def from_view(view: dict) -> dict:
    """Every number the pages may quote from a view (display units; see the key names):
    the rungs' values and steps, both engines together, the rungs' models, the answer's
    gaps, the truth and the identification, the mechanism, the record fits, the checks and
    the contact scan."""
    out: dict = {}
    trees = view["trees"]
    groups = sorted({g for t in trees.values() for g in t["rungs"]})
    metrics = sorted({m for t in trees.values() for r in t["rungs"].values()
                      for m in r["values"]})
    _rung_values(out, trees, groups, metrics)
    _engines_together(out, trees, metrics)
    _rung_models(out, trees, groups)
    _answer_gaps(out, trees)
    _truth_and_identification(out, trees)
    _mechanism(out, trees)
    _record_fits(out, trees)
    _checks(out, view.get("verdicts"))
    _contact_scan(out, view.get("scans") or {})
    return out


def _rung_values(out: dict, trees: dict, groups: list, metrics: list) -> None:
    """value.<rung>.<metric> (display units) and step_pct.<rung>.<metric> (the step from
    the rung below, %), per tree and spanned."""
    for g in groups:
        for m in metrics:
            scale = DISPLAY.get(m, (1.0, ""))[0]
            vals, steps = {}, {}
            for name, t in trees.items():
                r = t["rungs"].get(g)
                if r is None:
                    continue
                v = r["values"].get(m)
                vals[name] = scale * v if finite(v) else None
                s = (r["steps"] or {}).get(m)
                steps[name] = 100.0 * s if finite(s) else None
            per_tree(out, f"value.{g}.{m}", vals)
            if any(finite(v) for v in steps.values()):
                per_tree(out, f"step_pct.{g}.{m}", steps)


def _engines_together(out: dict, trees: dict, metrics: list) -> None:
    """Both engines together (a range over MuJoCo and Bullet and the trees), and MuJoCo
    against Bullet on the same rung (%)."""
    for kind in ("engine", "chain", "pendulum"):
        for m in metrics:
            steps = [100.0 * r["steps"][m] for t in trees.values()
                     for e in ("mujoco", "bullet") for r in [t["rungs"].get(f"{e}.{kind}")]
                     if r is not None and finite((r["steps"] or {}).get(m))]
            put(out, f"step_pct.engines.{kind}.{m}", span(steps))
            scale = DISPLAY.get(m, (1.0, ""))[0]
            put(out, f"value.engines.{kind}.{m}", span([
                scale * r["values"][m] for t in trees.values() for e in ("mujoco", "bullet")
                for r in [t["rungs"].get(f"{e}.{kind}")]
                if r is not None and finite(r["values"].get(m))]))
            put(out, f"abs.step_pct.engines.{kind}.{m}", span([abs(s) for s in steps]))
    for kind in ("engine", "chain", "pendulum"):
        for m in metrics:
            diffs = []
            for t in trees.values():
                a, b = t["rungs"].get(f"mujoco.{kind}"), t["rungs"].get(f"bullet.{kind}")
                if a and b and finite(a["values"].get(m)) and finite(b["values"].get(m)) \
                        and a["values"][m]:
                    diffs.append(abs(100.0 * (b["values"][m] / a["values"][m] - 1.0)))
            put(out, f"engines_agree_pct.{kind}.{m}", span(diffs))


def _rung_models(out: dict, trees: dict, groups: list) -> None:
    """Each rung's first contact (ms) and pad (effective mass, damping ratio, damping), and
    how much the convention rung's recalibration drops the pad's damping."""
    for name, t in trees.items():
        rungs = t["rungs"]
        for g, r in rungs.items():
            if finite(r.get("first_contact")):
                out[f"first_contact_ms.{g}.{name}"] = rounded(1e3 * r["first_contact"])
            for key in ("effective_mass", "pad_damping_ratio", "contact_damping"):
                if finite(r["model"].get(key)):
                    out[f"model.{g}.{key}.{name}"] = rounded(r["model"][key])
    for g in groups:
        for key in ("effective_mass", "pad_damping_ratio"):
            put(out, f"model.{g}.{key}", span([out.get(f"model.{g}.{key}.{t}")
                                               for t in trees]))
        put(out, f"first_contact_ms.{g}", span([out.get(f"first_contact_ms.{g}.{t}")
                                                for t in trees]))
    # the convention rung recalibrates only the pad's damping: how much it drops
    drops = {t: out.get(f"model.beam.contact_damping.{t}", math.nan)
             / out.get(f"model.convention.contact_damping.{t}", math.nan) for t in trees}
    per_tree(out, "pad_damping_drop", drops)


def _answer_gaps(out: dict, trees: dict) -> None:
    """The answer table: the continuum's gap to the paper's 1-DOF model (%), and the 1-DOF
    model's peak force and crown acceleration over the continuum's."""
    ratios = []
    for name, t in trees.items():
        a = t.get("answer")
        if not a:
            continue
        for m, row in a["metrics"].items():
            out[f"gap_pct.{m}.{name}"] = rounded(100.0 * row["rel"])
            if m in ("peak_force", "crown_peak_acceleration") and row["flexible"]:
                ratio = row["one_dof"] / row["flexible"]
                out[f"ratio.{m}.{name}"] = rounded(ratio)
                ratios.append(ratio)
    if trees and all(t.get("answer") for t in trees.values()):
        for m in next(iter(trees.values()))["answer"]["metrics"]:
            per_tree(out, f"gap_pct.{m}", {n: out.get(f"gap_pct.{m}.{n}") for n in trees})
    put(out, "ratio.force_and_acceleration", span(ratios))


def _truth_and_identification(out: dict, trees: dict) -> None:
    """The scenarios' own 1-DOF model (the identification's truth) and the paper's
    procedure's M_T error on the exact (Newton) record (%)."""
    for k in TRUTH_KEYS:
        per_tree(out, f"truth.{k}", {n: t["truth"].get(k) for n, t in trees.items()})
    errs = {}
    for name, t in trees.items():
        r = t["rungs"].get("newton")
        if r and finite(r["values"].get("id_M_T")) and finite(t["truth"].get("M_T")):
            errs[name] = 100.0 * (r["values"]["id_M_T"] / t["truth"]["M_T"] - 1.0)
    per_tree(out, "ident_error_pct.M_T", errs)
    put(out, "ident_error_pct.M_T.measured_trees",
        span([errs.get("open-center"), errs.get("central-leader")]))


def _mechanism(out: dict, trees: dict) -> None:
    """The 1-DOF model with the continuum's loss (docs/whole-event-metrics.md): e* and the
    gaps at e and at e* (%)."""
    for name, t in trees.items():
        mech = t.get("mechanism")
        if not mech or mech.get("error"):
            continue
        out[f"mechanism.e_star.{name}"] = rounded(mech["matched_restitution"])
        for row in mech["rows"]:
            out[f"mechanism.gap_pct.{row['metric']}.{name}"] = rounded(100.0 * row["gap"])
            out[f"mechanism.matched_gap_pct.{row['metric']}.{name}"] = rounded(
                100.0 * row["matched_gap"])
    for m in ("energy_delivered", "x_max", "crown_peak"):
        vals = [out.get(f"mechanism.matched_gap_pct.{m}.{n}") for n in trees]
        put(out, f"abs.mechanism.matched_gap_pct.{m}",
            span([abs(v) for v in vals if v is not None]))


def _record_fits(out: dict, trees: dict) -> None:
    """The exact 1-DOF model fitted to each rung's record (the report's record fits): how
    many fits of 1-DOF records explain them and their largest error (%), and how many of
    the flexible trunks' records are explained."""
    sdof, flexible = [], []
    for name, t in trees.items():
        ids = {r["id"]: g for g, r in t["rungs"].items()}
        for f in t.get("record_fits") or []:
            g = ids.get(f.get("rung"), "")
            if not f.get("errors"):
                continue
            if g in ("newton", "contact") or g.endswith(".engine"):
                sdof += [abs(100.0 * v) for v in f["errors"].values() if finite(v)]
                out.setdefault("record_fit.sdof_explained", 0)
                out["record_fit.sdof_explained"] += int(bool(f.get("explained")))
                out.setdefault("record_fit.sdof_fits", 0)
                out["record_fit.sdof_fits"] += 1
            else:
                flexible.append(bool(f.get("explained")))
    if sdof:
        out["record_fit.sdof_max_error_pct"] = rounded(max(sdof))
    if flexible:
        out["record_fit.flexible_fits"] = len(flexible)
        out["record_fit.flexible_explained"] = sum(flexible)


def _checks(out: dict, verdicts: dict | None) -> None:
    """The whole run's checks: how many, and how many (and %) of each verdict."""
    if verdicts:
        total = sum(verdicts.values())
        out["checks.total"] = total
        for k, v in verdicts.items():
            out[f"checks.{k}"] = v
            out[f"checks.{k}_pct"] = rounded(100.0 * v / total)
        out.setdefault("checks.n/a", 0)


def _contact_scan(out: dict, scans: dict) -> None:
    """The contact scan: from which pad duration (ms) the 1-DOF model is within the
    tolerance, per metric and tree, and the scan's range."""
    for name, s in scans.items():
        longest = 1e3 * s["durations"][-1]
        out["scan.longest_ms"] = rounded(longest)
        out["scan.shortest_ms"] = rounded(1e3 * s["durations"][0])
        out["scan.points"] = len(s["durations"])
        out["scan.range_ms"] = rounded([1e3 * s["durations"][0], longest])
        for m, d in s["shortest"].items():
            if d is None:
                out[f"scan.{m}.{name}.not_up_to_ms"] = rounded(longest)
            else:
                out[f"scan_ms.{m}.{name}"] = rounded(1e3 * d)
    for m in {m for s in scans.values() for m in s["shortest"]}:
        put(out, f"scan_ms.{m}", span([out.get(f"scan_ms.{m}.{n}") for n in scans]))
        vals = [out.get(f"scan_ms.{m}.{n}") for n in TREES]
        if all(v is not None for v in vals):
            put(out, f"scan_ms.{m}.trees", vals)


def from_small_e(trees: dict) -> dict:
    """The small-e answer (compare.studies.small_e; report.json's answer.small_e): per approximation
    and tree the largest e it holds up to (1, rounded down to 0.01 as the page prints it),
    its error at e = 0 and at the tree's own e (%), and their spans over the trees."""
    out: dict = {}
    for tree, answers in trees.items():
        for name, a in answers.items():
            out[f"small_e.{name}.holds_up_to_e.{tree}"] = rounded(
                math.floor(100.0 * a["holds_up_to_e"] + 1e-9) / 100.0)
            if "steady_up_to_e" in a:
                out[f"small_e.{name}.steady_up_to_e.{tree}"] = rounded(
                    math.floor(100.0 * a["steady_up_to_e"] + 1e-9) / 100.0)
            for key, v in (("error_at_zero_pct", a["error_at_zero"]),
                           ("error_at_e_pct", a["error_at_e"])):
                if finite(v):
                    out[f"small_e.{name}.{key}.{tree}"] = rounded(100.0 * v)
    names = {k.split(".")[1] for k in out}
    for name in names:
        for key in ("holds_up_to_e", "steady_up_to_e", "error_at_zero_pct",
                    "error_at_e_pct"):
            put(out, f"small_e.{name}.{key}",
                 span([out.get(f"small_e.{name}.{key}.{t}") for t in trees]))
    return out


def from_sensitivity(report: dict) -> dict:
    """The answer's ranges over the unmeasured inputs (the study's Morris screening)."""
    out: dict = {}
    for a in report["answer"]["one_dof"]:
        for key, sv in (a.get("sensitivity") or {}).items():
            name = key.split(".", 1)[1]
            out[f"sensitivity_pct.{name}.{a['scenario']}"] = rounded(
                [100.0 * sv["low"], 100.0 * sv["high"]])
    for name in {k.split(".")[1] for k in out}:
        rows = [out.get(f"sensitivity_pct.{name}.{t}") for t in TREES]
        rows = [r for r in rows if r]
        put(out, f"sensitivity_pct.{name}.low", span([r[0] for r in rows]))
        put(out, f"sensitivity_pct.{name}.high", span([r[1] for r in rows]))
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
            out[f"{key}.within_pct"] = rounded(100.0 * r["within"])
            out[f"{key}.cells"] = r["cells"]
            out[f"{key}.worst_pct"] = rounded(100.0 * r["worst_rel"])
            if v["target"] in ("mujoco", "bullet"):
                engines.setdefault(r["metric"], []).append(abs(100.0 * r["worst_rel"]))
    for m, vals in engines.items():
        out[f"study.engines.{m}.abs_worst_pct"] = rounded(max(vals))
    return out
