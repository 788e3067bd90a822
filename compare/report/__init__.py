"""The discrepancy report: ``report.html`` and ``report.md`` (the same figures, PNG files in
``figures/`` beside them) and ``report.json`` (every number of the page).

Sections, one module each, each a class with a jinja2 template under ``templates/``:

* :mod:`.paper` - Table 1 printed vs recomputed and the paper's discrepancies;
* :mod:`.scenario` - per scenario: Figs 4-5 redrawn for every rung, contact force, impact
  sequence, energy ledger, the ladder table, identification against the truth;
* :mod:`.trunks` - which MuJoCo trunk (hinged chain or elastic rod), how many segments,
  which step and at what cost, from the package's ``data/trunks.json`` (bench_trunks.py's);
* :mod:`.studies` - one per model-validity study directory given;
* :mod:`.runlog` - every backend run, its status (skips with their reasons) and wall time.

How the page is laid out (tables in scroll boxes, the run list, the figures): docs/report.md.

The runs come from a :class:`compare.runs.cache.RunCache` (``runs``), by default the session
cache that ``pytest compare`` fills, so ``pytest compare --report DIR`` reuses its runs.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import math
import shutil
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from treeimpact.analytic.model.plausible import implausible
from treeimpact.analytic.model.reduction import mass_parts
from treeimpact.analytic.model.registry import BY_PATH
from treeimpact.analytic.model.scenario import assumed_fields, shipped_scenarios
from treeimpact.analytic.results import json_text

from ..runs.cache import RunCache, resolve_scenario
from ..runs.pool import check_stop, preload_in_workers, process_map
from ..runs.progress import Progress, plan
from ..runs.provenance import provenance, scenario_digest
from ..runs.verdicts import Verdict, validity_tolerance
from ..studies.contact_scan import scan_result, scan_sweep
from ..studies.ident_fits import fit_one, fit_tasks
from ..studies.small_e import E_GRID, RESOLUTION, small_e_answer, small_e_sweep
from ..studies.sweep.run import run_sweeps
from ..tree.ladder import build_ladder, prefetch_ladders
from .answer import (
    ANSWER_METRICS,
    ANSWER_TERMS,
    grid_text,
    in_short,
    one_dof_answer,
    small_e_rows,
    with_sensitivity,
)
from .base import environment, num
from .design_answer import design_answer
from .design_answer import in_short_text as design_in_short
from .first_screen import first_screen, with_ranges
from .measure import in_short_text, with_sobol
from .pageset import clear_leftovers, staged, swap_in
from .paper import PaperSection
from .runlog import RunsSection
from .sort_keys import add_sort_keys
from .studies import StudySection
from .trunks import TrunksSection

__all__ = ["write_report", "build_sections"]

#: The folder of the report's own sweeps (contact scans, identification against e).
SWEEPS = "sweeps"


def build_sections(scenarios=None, study_dirs=(), runs=None, *, engines=None, segments=None,
                   out_dir=None, figure_dir=None, progress: bool = False,
                   study_jobs=()) -> dict:
    """The report's sections (not yet rendered) and the wall time each took (s), for the
    ``scenarios``, ``study_dirs``, ``runs``, ``engines`` and ``segments`` of
    :func:`write_report`; figures are written to ``figure_dir`` (default
    ``out_dir/figures``; none without either), the pages linking them as ``figures/`` of
    the page's folder ``out_dir``; ``progress``: runs and
    sections reported on stderr as they finish; ``study_jobs``: studies running beside the
    report (compare.report.validity.study_job.StudyJob), each a section once it ends."""
    # lazy: +291 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from .figures import FigureFiles

    studies = [StudySection(d, page_dir=out_dir) for d in study_dirs]  # read (and refused)
    # before any run
    # the record fits' modules (scipy.optimize) imported once by the forkserver the runs start
    preload_in_workers("treeimpact.compare.studies.ident_fits",
                       "treeimpact.analytic.identify.record_fit")
    cache = RunCache() if runs is None else runs
    if figure_dir is None and out_dir is not None:
        figure_dir = Path(out_dir) / "figures"
    sink = FigureFiles(figure_dir) if figure_dir is not None else None
    names = list(shipped_scenarios()) if not scenarios else list(scenarios)
    scens = [resolve_scenario(s) for s in names]
    wall = {}
    t0 = time.perf_counter()
    if progress:
        plan(4)  # the report's stages: runs, sweeps, record fits, sections (compare.runs.progress)
    prefetch_ladders(cache, scens, engines=engines, segments=segments, progress=progress)
    wall["runs (process pool)"] = time.perf_counter() - t0
    for job in study_jobs:  # a study that failed meanwhile fails the report now
        job.check()
    t0 = time.perf_counter()
    contact, small_e, e_tables = _report_sweeps(scens, out_dir, sink, progress)
    wall["sweeps (contact scan, the small-e curves)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    paper = PaperSection()
    wall["paper"] = time.perf_counter() - t0
    scen_sections = _scenario_sections(scens, cache, e_tables, sink, wall, engines=engines,
                                       segments=segments, progress=progress)
    # lazy: +600 ms at import otherwise (matplotlib, scipy, numpy),
    # which this module's other callers do not need
    from .answer_matrix import answer_matrix

    matrix = answer_matrix(scen_sections, small_e["trees"], sink)
    trunks = TrunksSection(tree=scens[0].name if scens else None)
    t0 = time.perf_counter()
    for job in study_jobs:
        studies.append(StudySection(job.result(), page_dir=out_dir))
        wall[f"study {job.preset} (a child process beside all of the above, from its start "
             "to its end)"] = job.wall_s
    if study_jobs:
        wall["waiting for the studies"] = time.perf_counter() - t0
    log = RunsSection(cache, wall)
    return {"paper": paper, "scenarios": scen_sections, "trunks": trunks, "studies": studies,
            "runs": log, "contact": contact, "small_e": small_e, "answer_matrix": matrix}


def _report_sweeps(scens: list, out_dir, sink, progress: bool) -> tuple[dict, dict, dict]:
    """The report's own sweeps of the scenarios ``scens``, on one pool (into
    ``out_dir/sweeps``, or a temporary folder without ``out_dir``): the contact scans and
    the small-e curves, their figures given to ``sink`` (None: not drawn); ``progress``: a
    bar on a terminal. Returns (contact {scans, figure}, small_e {trees, figure}, the e
    sweeps' tables by scenario name)."""
    # lazy: +314 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from .answer_figures import small_e_figure

    # lazy: +291 ms at import otherwise (matplotlib, numpy),
    # which this module's other callers do not need
    from .summary_figures import contact_scan_figure

    with _sweep_dir(out_dir) as folder:  # the tables are read before a temporary one goes
        specs = [scan_sweep(s, folder / f"contact-scan-{s.name}") for s in scens] + [
            small_e_sweep(s, folder / f"small-e-{s.name}") for s in scens]
        done = run_sweeps(specs, progress=None if progress else False)  # a bar on a terminal only
    scans = {s.name: scan_result(r.table) for s, r in zip(scens, done)}
    e_tables = {s.name: r.table for s, r in zip(scens, done[len(scens):])}
    small_e = {s.name: small_e_answer(s, e_tables[s.name]) for s in scens}
    shipped_pads = {s.name: s.contact.duration for s in scens}
    scan_figure = sink(contact_scan_figure(scans, shipped_pads), "contact-scan") if sink \
        else None
    small_e_fig = sink(small_e_figure(small_e, validity_tolerance()), "small-e") if sink \
        else None
    return ({"scans": scans, "figure": scan_figure}, {"trees": small_e, "figure": small_e_fig},
            e_tables)


def _scenario_sections(scens: list, cache, e_tables: dict, sink, wall: dict, *, engines,
                       segments, progress: bool) -> list:
    """One section per scenario of ``scens``: its ladder (runs from ``cache``, with the
    ``engines`` and ``segments`` asked for) drawn with its e sweep's table (``e_tables``)
    into ``sink``, while every rung's record is fitted in a process pool; the wall time of
    each step added to ``wall`` (s); ``progress``: bars on stderr."""
    # lazy: +655 ms at import otherwise (matplotlib, scipy, numpy),
    # which this module's other callers do not need
    from .scenario import ScenarioSection, identification_sweep

    # every rung's record fitted, all scenarios in one process pool, while this process
    # draws the sections' figures (the fits are read only when the page is rendered)
    t_fits = time.perf_counter()
    kw = {} if engines is None else {"engines": engines}
    ladders = [build_ladder(s, cache=cache, segments=segments, **kw) for s in scens]
    tasks = [fit_tasks(ladder) for ladder in ladders]
    flat = [task for ts in tasks for task in ts]
    fit_bar = Progress(len(flat), "record fits", unit="fit") if progress else None
    scen_sections = []
    with ThreadPoolExecutor(1) as fitter:
        pending = fitter.submit(process_map, fit_one, flat,
                                done=fit_bar.update if fit_bar else None)
        bar = Progress(len(scens), "report sections", unit="scenario") if progress else None
        for scen, ladder in zip(scens, ladders):
            t0 = time.perf_counter()
            scen_sections.append(ScenarioSection(
                ladder, identification_sweep(e_tables[scen.name]), figure_sink=sink, fits=[]))
            wall[f"scenario {scen.name} (figures, beside the fits)"] = \
                time.perf_counter() - t0
            check_stop()
            if bar is not None:
                bar.update()
        if bar is not None:
            bar.close()
        done_fits = iter(pending.result())
    if fit_bar is not None:
        fit_bar.close()
    for section, ts in zip(scen_sections, tasks):
        section.fits = [next(done_fits) for _ in ts]
    wall["record fits (process pool)"] = time.perf_counter() - t_fits
    return scen_sections


@contextlib.contextmanager
def _sweep_dir(out_dir):
    """``out_dir/sweeps``, or a temporary directory removed afterwards (no ``out_dir``)."""
    if out_dir is not None:
        yield Path(out_dir) / SWEEPS
        return
    with tempfile.TemporaryDirectory(prefix="treeimpact-sweeps-") as tmp:
        yield Path(tmp)


def _page_summary(sections: dict) -> dict:
    """What the page's first screen and answer read from the built ``sections``: the ladder
    summary, the answer rows with their sensitivity, the contact scan, the small-e table,
    and the answer in short."""
    summary = _summary(sections["scenarios"])
    summary["answer"] = one_dof_answer(sections["scenarios"])
    with_sensitivity(summary["answer"], sections["studies"])
    with_sobol(summary["answer"], sections["studies"])
    summary["answer_metrics"] = ANSWER_METRICS
    summary["answer_terms"] = ANSWER_TERMS
    summary["answer_tolerance"] = validity_tolerance()
    summary["contact"] = sections["contact"]
    summary["answer_matrix"] = sections["answer_matrix"]
    small_e = sections["small_e"]
    summary["small_e"] = {**small_e, "rows": small_e_rows(small_e["trees"]),
                          "step": E_GRID[1] - E_GRID[0], "e_max": E_GRID[-1],
                          "grid": grid_text(E_GRID), "resolution": RESOLUTION}
    summary["in_short"] = in_short(summary["answer"], small_e["trees"])
    measure = in_short_text(summary["answer"])
    if measure:
        summary["in_short"]["measure_first"] = measure
    summary["design"] = design_answer(sections["studies"])
    if summary["design"]:
        summary["in_short"]["design"] = design_in_short(summary["design"])
    summary["answer_ranges"] = with_ranges(summary["answer"])
    summary["first_screen"] = first_screen(summary, sections["scenarios"])
    summary["implausible"] = {s.ladder.name: found for s in sections["scenarios"]
                              if (found := [i.text for i in implausible(s.ladder.scenario)])}
    summary["mass_origin"] = {s.ladder.name: mass_origin(s.ladder.scenario.trunk,
                                                         assumed_fields(s.ladder.scenario))
                              for s in sections["scenarios"]}
    return summary


def mass_origin(trunk, assumed=()) -> str:
    """Where ``trunk``'s M_T comes from (eq 7), in one line: its three parts and how many
    times the crown's mass counts (phi(l)^2, the crown's static motion per unit x at the
    clamp, squared); for a tree from its geometry, the trunk fields it ``assumed``
    (``[calibration] assumed``: no pendulum test measured M_T, K_T or C_T)."""
    p = mass_parts(trunk)
    text = (f"M_T = {num(p.total, 3)} kg = {num(p.trunk, 3)} kg of trunk + {num(p.clamp, 3)} kg "
            f"of clamp + {num(p.crown, 3)} kg of crown ({num(trunk.crown_mass, 3)} kg counted "
            f"{num(p.crown_weight, 3)} times: the crown moves {num(p.crown_weight ** 0.5, 3)} "
            "times the clamp in the static shape)")
    if assumed:
        text += ("; from its geometry and a crown estimate, no pendulum test: "
                 f"{', '.join(BY_PATH[f].label for f in assumed)} assumed (the file's "
                 "[calibration] gives each value, range and reason)")
    return text


def write_report(out_dir, scenarios=None, study_dirs=(), runs=None, **options) -> dict:
    """Write report.html, report.md and report.json into ``out_dir`` (created if needed).

    ``scenarios``: shipped names, TOML paths or Scenario objects (default: the shipped
    scenarios); ``study_dirs``: directories of model-validity studies; ``runs``: the
    :class:`compare.runs.cache.RunCache` to take runs from (default: a new one).
    ``options`` (:func:`build_sections`'): ``engines`` (tuple of engine backends) and
    ``segments`` (hinged trunk) go to the ladder; ``progress``; ``study_jobs``: studies
    running beside the report (compare.report.validity.study_job.StudyJob), included when they end.
    Returns ``{"html": Path, "md": Path, "json": Path}``; figures go to
    ``out_dir/figures``. The pages and figures are one set (:mod:`.pageset`): written into a
    temporary folder inside ``out_dir`` and swapped into place together, so an interrupt or
    a failure leaves the earlier report's set as it was.
    """
    t_start = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    clear_leftovers(out)
    shutil.rmtree(out / SWEEPS, ignore_errors=True)  # its sweeps: rows of older code
    with staged(out) as stage:
        sections = build_sections(scenarios, study_dirs, runs, out_dir=out,
                                  figure_dir=stage / "figures", **options)
        _write_pages(stage, sections, t_start)
        placed = swap_in(stage, out)
    return {fmt: placed[f"report.{fmt}"] for fmt in ("html", "md", "json")}


def _write_pages(folder: Path, sections: dict, t_start: float) -> None:
    """report.html, report.md and report.json of the built ``sections`` into ``folder``;
    ``t_start``: when the report began (time.perf_counter, s), for its total wall time."""
    ordered = [sections["paper"], *sections["scenarios"], sections["trunks"],
               *sections["studies"], sections["runs"]]
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    summary = _page_summary(sections)
    env = environment()
    for fmt in ("html", "md"):
        parts = [(s, s.render(fmt)) for s in ordered]
        page = env.get_template(f"report.{fmt}.j2").render(
            sections=ordered, parts=parts, generated=stamp, summary=summary)
        if fmt == "html":  # every numeric cell its number in SI for the sorter
            page = add_sort_keys(page)
        (folder / f"report.{fmt}").write_text(page, encoding="utf-8")
    sections["runs"].wall_s["total"] = time.perf_counter() - t_start
    data = _report_data(sections, summary, stamp)
    (folder / "report.json").write_text(json_text(data, indent=1), encoding="utf-8")


def _report_data(sections: dict, summary: dict, stamp: str) -> dict:
    """report.json's content: the built ``sections`` with the page's ``summary``
    (:func:`_page_summary`), generated at ``stamp``."""
    small_e = sections["small_e"]
    return {
        "generated": stamp,
        "provenance": provenance(scenarios={s.ladder.name: scenario_digest(s.ladder.scenario)
                                            for s in sections["scenarios"]}),
        "tolerances": "compare/runs/tolerances.toml",
        "answer": {"tolerance": summary["answer_tolerance"], "in_short": summary["in_short"],
                   "one_dof": summary["answer"], "small_e": small_e["trees"],
                   "small_e_figure": small_e["figure"],
                   "measure_first": {a["scenario"]: a["measure_first"]
                                     for a in summary["answer"] if a.get("measure_first")},
                   "design": summary["design"], "first_screen": summary["first_screen"],
                   "ranges": summary["answer_ranges"]},
        "summary": {k: v for k, v in summary.items()
                    if k not in ("answer", "small_e", "in_short", "answer_tolerance", "design",
                                 "first_screen", "answer_ranges", "answer_terms")},
        "paper": sections["paper"].to_json(),
        "scenarios": {s.ladder.name: s.to_json() for s in sections["scenarios"]},
        "trunks": sections["trunks"].to_json(),
        "studies": [s.to_json() for s in sections["studies"]],
        "runs": sections["runs"].to_json(),
    }


#: How many of the largest discrepancies the summary lists, whatever their verdict.
LARGEST = 12


def _summary(scen_sections) -> dict:
    """Counts of verdicts over all checks, the findings, the rungs not run, and the
    :data:`LARGEST` largest relative discrepancies between rungs whatever their verdict
    (the identification has its own table per scenario)."""
    counts: dict = {}
    findings, problems, skipped = [], [], []
    for s in scen_sections:
        for c in s.checks:
            counts[c.verdict] = counts.get(c.verdict, 0) + 1
            if c.finding:
                findings.append({"scenario": c.scenario, "rung": c.rung, "metric": c.metric,
                                 "finding": c.finding, "rel_diff": c.rel_diff,
                                 "verdict": c.verdict,
                                 "css": "finding" if c.verdict == Verdict.FINDING else "flag"})
            elif c.verdict.flagged:
                problems.append({"scenario": c.scenario, "rung": c.rung, "metric": c.metric,
                                 "rel_diff": c.rel_diff, "tolerance": c.tolerance,
                                 "verdict": c.verdict, "reason": c.reason})
        for r in s.ladder.rungs:
            if not r.ok:
                skipped.append({"scenario": s.ladder.name, "rung": r.rung.id,
                                "status": r.status, "reason": r.reason})
    largest = sorted((c for s in scen_sections for c in s.checks
                      if not c.metric.startswith("id_") and isinstance(c.rel_diff, float)
                      and math.isfinite(c.rel_diff)),
                     key=lambda c: -abs(c.rel_diff))[:LARGEST]
    return {"verdicts": counts, "findings": findings, "problems": problems,
            "not_run": skipped,
            "largest": [{"scenario": c.scenario, "rung": c.rung, "metric": c.metric,
                         "reference": c.reference, "rel_diff": c.rel_diff,
                         "verdict": c.verdict, "reason": c.reason} for c in largest]}
