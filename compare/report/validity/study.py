"""Model-validity studies: sweeps + validity maps + identification maps + speed curves.

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from treeimpact.analytic.errors import NotAchieved
from treeimpact.analytic.results import json_text
from treeimpact.compare.report.base import environment
from treeimpact.compare.runs.backends import ENGINES
from treeimpact.compare.runs.cache import OK
from treeimpact.compare.runs.provenance import provenance
from treeimpact.compare.runs.rungs import RungKind
from treeimpact.compare.studies.ident_study import (
    ENGINE_CROWN_RATIOS,
    ENGINE_RESTITUTIONS,
    NOISE,
    RATE,
    RUNGS,
    SAMPLING_E,
    run_identification_study,
)

from ...studies.speed import speed_curves, speed_sweep
from ...studies.sweep.journal import JOURNAL, TABLE, make_out, read_file, read_table
from ...studies.sweep.maps import (
    DEFAULT_TOLERANCE,
    identification_maps,
    point_text,
    validity_maps,
)
from ...studies.sweep.run import SweepSpec, run_sweep, run_sweeps
from .presets import (  # noqa: F401 - the study's presets, re-exported
    PRESETS,
    Preset,
    get_preset,
)
from .sensitivity_study import sensitivity_result, sensitivity_specs


def run_study(out, preset: str = "default", *, scenario=None, backends=None, workers=None,
              scheduler=None, progress=None, tolerance=None, grid=None,
              retry_failed: bool = False, sensitivity_scenarios=None) -> dict:
    """Run (or resume) a preset's sweeps into ``out`` and write the study; returns the paths.
    ``scenario``, ``backends`` (its engines among them) and ``grid`` replace the preset's;
    ``tolerance``: the maps' criterion (None: the default); ``workers``, ``scheduler``,
    ``progress`` and ``retry_failed`` as :func:`compare.studies.sweep.run.run_sweeps`.
    ``sensitivity_scenarios``: the trees of its sensitivity study (shipped names, TOML paths
    or Scenarios; default: every shipped tree). What its caller gives is checked where it
    enters, by the public API's study (compare.interface.api_studies): the backends' names,
    the grid, what a study of another kind fixes (its backends, tolerance and sensitivity
    trees, ignored here)."""
    p = get_preset(preset)
    if p.run is not None:  # a study of another kind: its module runs it
        return p.run(out, scenario or p.scenario, workers=workers, scheduler=scheduler,
                     progress=progress, grid=grid, retry_failed=retry_failed)
    return _validity_study(out, p, scenario=scenario, backends=backends, workers=workers,
                           scheduler=scheduler, progress=progress, tolerance=tolerance,
                           grid=grid, retry_failed=retry_failed,
                           sensitivity_scenarios=sensitivity_scenarios)


def _validity_study(out, p: Preset, *, scenario, backends, workers, scheduler, progress,
                    tolerance, grid, retry_failed, sensitivity_scenarios) -> dict:
    """:func:`run_study` of a validity preset ``p`` (the sweeps, speed, identification and
    sensitivity parts it asks for)."""
    t0 = time.perf_counter()
    out = make_out(out)
    scen = scenario or p.scenario
    engines = tuple(b for b in (backends or p.engines) if b in ENGINES)
    sweeps = {}
    done = []  # the SweepResults of the study's table: what this run computed, what it found
    # the sensitivity study's sweeps (one per tree) share the validity sweep's pool
    sens = sensitivity_specs(out, p.sensitivity, crossings=p.sensitivity_crossings,
                             scenarios=sensitivity_scenarios, sobol=p.sobol) \
        if p.sensitivity else None
    with_sens = sens["specs"] if sens else []
    validity_backends = p.backends if p.engine_grid else (*p.backends, *engines)
    first = run_sweeps([SweepSpec(scen, list(grid or p.grid), out / "validity",
                                  backends=validity_backends, ladder=p.ladder), *with_sens],
                       workers=workers, scheduler=scheduler, progress=progress,
                       retry_failed=retry_failed)
    res, sens_done = first[0], first[1:]
    sweeps["validity"] = res.out
    done.append(res)
    if p.engine_grid and engines:  # references on the fine grid, engines on a coarse one
        eng = run_sweep(scen, list(p.engine_grid), out / "engines",
                        backends=(*p.backends, *engines), ladder=p.ladder,
                        workers=workers, scheduler=scheduler, progress=progress,
                        retry_failed=retry_failed)
        sweeps["engines"] = eng.out
        done.append(eng)

    speed = None
    if p.speed and engines:
        speed = speed_sweep(scen, out, engines=engines, dts=p.speed_dts,
                            durations=p.speed_durations, progress=progress)
        speed["curves"] = speed_curves(speed, out)
    ident_study = None
    if p.identification:
        ident_study = run_identification_study(
            out, scen, workers=workers, progress=progress,
            sampling_rungs=p.ident_sampling_rungs, engine_rungs=p.ident_engine_rungs,
            sampling_seeds=p.ident_sampling_seeds, crown_ratios=p.ident_crown_ratios)
    sensitivity = sensitivity_result(out, sens, sens_done) if sens else None
    paths = write_study(out, sweeps, speed=speed, tolerance=tolerance,
                       metrics=p.map_metrics, value=p.map_value, ident_study=ident_study,
                       sensitivity=sensitivity,
                       title=f"Model-validity study ({p.name} preset)",
                       meta={"preset": p.name, "expected_run_time": p.expected,
                             "wall_s": time.perf_counter() - t0,
                             "rows_written": sum(r.rows_written for r in done),
                             "rows_done_before": sum(r.rows_done_before for r in done)})
    return _points_said(paths, sensitivity, out)


def _points_said(paths: dict, sensitivity: dict | None, out: Path) -> dict:
    """The written study's ``paths`` with ``warnings``: one line per sensitivity design
    with a failed point (compare.report.validity.sensitivity_study.point_counts), which the
    command prints on stderr; NotAchieved (one line, after the pages are written into
    ``out``) when no point of the sensitivity study ran."""
    counts = (sensitivity or {}).get("points") or {}
    if counts.get("points") and not counts["ran"]:
        first = counts["lines"][0].split(" The first: ", 1)[-1] if counts["lines"] else ""
        raise NotAchieved(f"sensitivity: none of its {counts['points']} points ran, so no "
                          f"index; the first: {first}; the study is written in {out}")
    return {**paths, "warnings": list(counts.get("lines", []))}


def _combined_table(out: Path, sweeps: dict, speed: dict | None):
    # lazy: +216 ms at import otherwise (pandas, numpy, pyarrow),
    # which this module's other callers do not need
    import pandas as pd

    frames = []
    dirs = dict(sweeps)
    if speed:
        dirs.update({f"speed-{e}": d for e, d in speed["engines"].items()})
    for name, d in dirs.items():
        df = read_table(d)
        frames.append(df.assign(sweep=name))
    table = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    if list(dirs.values()) == [out]:  # a single sweep written into the study directory
        return out / TABLE, table
    for c in table.columns:
        if table[c].dtype == object:
            table[c] = table[c].astype("string")
    table.to_parquet(out / TABLE, index=False)
    table.to_csv(out / JOURNAL, index=False)
    return out / TABLE, table


def _fmt_point(point) -> str:
    """A grid point as 'name = value unit, ...' in the maps' display units (a contact
    duration in ms; the table stores the point as JSON pairs in SI)."""
    try:
        pairs = json.loads(point) if isinstance(point, str) else point
        return point_text(pairs)
    except (TypeError, ValueError):
        return str(point)


def _step_words(kind: str) -> str:
    """A rung kind's step in a few words ('1-DOF assumption'); the kind if unknown."""
    try:
        return RungKind(kind).step.split(" (")[0]
    except ValueError:
        return kind


def _letters_shown(validity: list[dict], value: str) -> list[dict]:
    """The rung letters the validity maps print (only maps against the paper's model print
    the dominating step's letter), each with its step, in ladder order."""
    if value != "rel":
        return []
    shown = {k for v in validity if v.get("path") for r in v["summary"] for k in r["dominant"]}
    return [{"letter": k.letter, "step": k.step} for k in RungKind if k.value in shown]


def write_study(out, sweeps: dict, *, speed: dict | None = None, tolerance=None,
                metrics=None, value: str = "rel", title: str = "Model-validity study",
                meta: dict | None = None, ident_study: dict | None = None,
                sensitivity: dict | None = None) -> dict:
    """Draw the maps of finished sweeps (``{name: sweep dir}``) and write study.md,
    study.html, study.json and the combined results table into ``out``.

    Args:
        out: the study's folder.
        sweeps: the finished sweeps, name -> folder.
        speed: :func:`speed_sweep`'s result with its curves, or None.
        tolerance: the maps' criterion (None: the default).
        metrics: the metrics mapped (None: every ladder metric).
        value: "rel" (against the paper's model) or "step" (against the rung below).
        title: the page's title.
        meta: more fields for study.json (the preset, its notes).
        ident_study: the identification validation's result, or None.
        sensitivity: the sensitivity study's result, or None.

    Returns:
        The written paths: md, html, json, table and the figures.
    """
    out = make_out(out)
    meta = dict(meta or {})
    table_path, table = _combined_table(out, sweeps, speed)
    validity, ident, specs = _draw_maps(out, sweeps, tolerance=tolerance, metrics=metrics,
                                        value=value)
    curves = (speed or {}).get("curves", [])
    status, timings, problems = _runs_of(table)
    summary = {
        "title": title, **meta, "sweeps": {n: {"scenario": s["scenario"]["name"],
                                               "grid": s["grid"]} for n, s in specs.items()},
        "rows": int(len(table)), "status": {str(k): int(v) for k, v in status.items()},
        "timings": timings,
        "tolerance": tolerance if tolerance is not None else DEFAULT_TOLERANCE,
        "validity": [{"target": v["target"], "figure": v["path"].name if v["path"] else None,
                      "summary": v["summary"]} for v in validity],
        "identification": [{"target": v["target"], "figure": v["path"].name,
                            "summary": v["summary"]} for v in ident],
        "speed": {"skipped": (speed or {}).get("skipped", []),
                  "figures": [c["path"].name for c in curves if c["path"]]},
        "problems": problems,
    }
    summary["map_value"] = value
    if sensitivity is not None:
        summary["sensitivity"] = sensitivity
    summary["provenance"] = provenance()
    if ident_study is not None:
        summary["identification_validation"] = {
            "summary": ident_study["summary"], "sampling": ident_study.get("sampling", []),
            "figures": [f.name for f in ident_study["figures"]]}
    summary.update(_presentation(summary, validity, ident, curves))
    (out / "study.json").write_text(json_text(summary, indent=2))
    (out / "study.md").write_text(render_study(summary, "md"))
    (out / "study.html").write_text(render_study(summary, "html"))
    return {"md": out / "study.md", "html": out / "study.html", "json": out / "study.json",
            "table": table_path,
            "figures": [v["path"] for v in validity + ident if v["path"]]
            + [c["path"] for c in curves if c["path"]]}


def _draw_maps(out: Path, sweeps: dict, *, tolerance, metrics, value: str) -> tuple:
    """The validity and identification maps of each finished sweep (``{name: sweep dir}``)
    drawn into ``out``, a target mapped once (from the first, finest sweep that has it);
    returns (validity maps, identification maps, each sweep's spec)."""
    validity, ident, specs = [], [], {}
    drawn = set()  # targets already mapped from an earlier (finer) sweep of the study
    for name, d in sweeps.items():
        df = read_table(d)
        specs[name] = read_file(Path(d) / "sweep.json",
                                lambda p: json.loads(p.read_text(encoding="utf-8")), "spec")
        prefix = "" if len(sweeps) == 1 or name == "validity" else f"{name}-"
        order = [t["id"] for t in specs[name].get("targets", [])]
        validity += validity_maps(df, out, tolerance=tolerance, prefix=f"{prefix}validity",
                                  order=order, value=value, skip=drawn,
                                  **({"metrics": metrics} if metrics else {}))
        ident += identification_maps(df, out, prefix=f"{prefix}identification", order=order,
                                     skip=drawn)
        drawn |= set(order)
    return validity, ident, specs


def _runs_of(table) -> tuple:
    """What the study's runs came to (its combined table): the count of each status, each
    backend's runs and mean wall time (s) over its distinct tasks that succeeded, and up to
    40 distinct failures (sweep, target, status, error)."""
    status = table["status"].value_counts().to_dict() if len(table) else {}
    timings = {}
    if len(table):
        ok = table[table["status"] == OK].drop_duplicates(subset=["task"])
        for b, g in ok.groupby("backend"):
            timings[b] = {"runs": int(len(g)), "mean_wall_s": float(g["wall_s"].astype(float)
                                                                    .mean())}
    problems = []
    if len(table):
        bad = table[table["status"] != OK].drop_duplicates(subset=["target", "error"])
        problems = [{"sweep": r["sweep"], "target": r["target"], "status": r["status"],
                     "error": r["error"]} for _, r in bad.head(40).iterrows()]
    return status, timings, problems


def render_study(summary: dict, fmt: str, *, level: int = 1, image=None) -> str:
    """The study page (``fmt`` "md" or "html") from its data ``summary`` (study.json), with
    the report's
    templates; ``level``: the title's heading level; ``image(name)``: a figure's link (the
    study's own directory by default)."""
    template = "study_body.md.j2" if fmt == "md" else "study_page.html.j2"
    return environment().get_template(template).render(s=summary, level=level,
                                                       image=image or (lambda name: name))


def _presentation(summary, validity, ident, curves) -> dict:
    """What the page shows beyond the numbers: captions, figure names, where the worst
    cells are, the texts around the tables (all kept in study.json)."""
    tol = summary["tolerance"]
    out = {
        "versus": ("Relative discrepancy (target - analytic) / |analytic| of each metric "
                   "from the paper's one-degree-of-freedom Newton-restitution model "
                   "(eqs 12-35).") if summary.get("map_value", "rel") == "rel" else (
            "Relative step of each target from the rung below it: soft vs analytic is the "
            "contact model, beam vs soft the 1-DOF assumption alone (the same pad), an "
            "engine's chain vs beam its discretisation and numerics."),
        "tolerance_text": str(tol) if isinstance(tol, dict) else f"{100 * tol:g} %",
        "rung_letters": _letters_shown(validity, summary.get("map_value", "rel")),
        "validity": [{"target": v["target"], "figure": v["path"].name if v["path"] else None,
                      "caption": v["caption"],
                      "summary": [{**r, "worst_at": _fmt_point(r["worst_point"]),
                                   "dominant_text": ", ".join(f"{_step_words(k)} {n}"
                                                              for k, n in
                                                              r["dominant"].items())}
                                  for r in v["summary"]]} for v in validity],
        "identification": [{"target": v["target"], "figure": v["path"].name,
                            "caption": v["caption"],
                            "summary": [{**r, "worst_at": _fmt_point(r["worst_point"])}
                                        for r in v["summary"]]} for v in ident],
        "speed": {**summary["speed"], "curves": [
            {"engine": c["engine"], "figure": c["path"].name if c["path"] else None,
             "caption": c["caption"],
             "error": "" if c["path"] else "; ".join(sorted(set(
                 c["points"]["error"].astype(str))))[:300]} for c in curves]},
    }
    iv = summary.get("identification_validation")
    if iv:
        out["identification_validation"] = {**iv, **_ident_validation_text(iv)}
    return out


def _ident_validation_text(iv) -> dict:
    """The identification validation's texts and table rows (compare.studies.ident_study)."""
    engines = [r for r in iv["summary"] if r not in RUNGS]
    corner = (f" (and of the {', '.join(engines)} hinged chain at e = "
              f"{', '.join(f'{e:g}' for e in ENGINE_RESTITUTIONS)} x crown ratio "
              f"{', '.join(f'{c:g}' for c in ENGINE_CROWN_RATIOS)})") if engines else ""
    rows = []
    for rung, entry in iv["summary"].items():
        for method in ("fit", "paper"):
            m = entry[method]
            one = "-"
            if method == "fit":
                one = str(m.get("not_fixed", 0)) + (
                    f" ({_fmt_abs(m['known_e_worst'])} / {_fmt_abs(m.get('with_y_worst'))})"
                    if m.get("not_fixed") else "")
            rows.append({"rung": rung, "method": method, "identified": m["identified"],
                         "cases": m["cases"], "within_goal": m["within_goal"],
                         "worst": m["worst"], "one_impact": one,
                         "covered": m.get("covered"), "explained": m.get("explained")})
    return {
        "text": (f"Records of the {', '.join(RUNGS)} rungs over e x crown ratio{corner}, "
                 f"sampled at {RATE / 1e3:g} kHz with {100 * NOISE:g} % noise (one seed), "
                 "identified both ways; errors against the SDOF truth (M_T, K_T and b = C_T / "
                 "(2 (M_T + m)), eq 42). explained: the fit's residual check says the 1-DOF "
                 "model explains the record; covered: the fit's 95 % intervals (ranges where "
                 "the record does not fix them) contain the truth (M_T, K_T, C_T). one "
                 "impact: records the pendulum leaves after one impact fix omega_1, xi and "
                 "V_1 = m (1 + e) u_1 / (M_T + m) but not M_T and e apart; the fit gives "
                 "ranges there (not counted in identified or the 2 % column); the worst error "
                 "with the pad's e given / with the pendulum's record y fitted too is shown."),
        "rows": rows,
        "sampling_text": (f"How the sampling matters: records at e = {SAMPLING_E:g}, no crown "
                          f"(analytic: the exact SDOF), {_seeds(iv)} per cell; "
                          "the fit's worst |error| over M_T, K_T and b, how often its 95 % "
                          "intervals cover the truth, and how often it says the 1-DOF model "
                          "explains the record."),
    }


def _seeds(iv) -> str:
    """'2 seeds' (or '1 seed'): the trials of the sampling table's cells."""
    n = max((c.get("trials", 0) for c in iv.get("sampling", [])), default=0)
    return f"{n} seed{'s' if n != 1 else ''}"


def _fmt_abs(v) -> str:
    return "n/a" if v is None or v != v else f"{v:.1%}"
