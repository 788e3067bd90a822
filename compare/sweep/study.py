"""Model-validity studies: sweeps + validity maps + identification maps + speed curves.

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

import html
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.backends import ENGINES
from treeimpact.compare.rungs import RungKind

from .maps import DEFAULT_TOLERANCE, identification_maps, validity_maps
from .run import JOURNAL, TABLE, make_out, read_table, run_sweep


@dataclass(frozen=True)
class Preset:
    name: str
    scenario: str
    grid: tuple  # --grid specs of the validity sweep
    ladder: bool = True
    engines: tuple = ENGINES
    speed: bool = True
    speed_dts: tuple = (1e-4, 3e-5, 1e-5)  # s
    speed_durations: tuple = (1e-3, 5e-4)  # s: contact durations giving the stiffnesses
    backends: tuple = ("analytic", "soft")  # reference backends of the validity sweep
    engine_grid: tuple = ()  # --grid specs of a coarser engine check (its own sweep)
    map_metrics: tuple | None = None  # metrics drawn on the maps (None: every ladder metric)
    map_value: str = "rel"  # "rel": against the paper's model; "step": against the rung below
    identification: bool = False  # the identification validation (compare.ident_study)
    ident_sampling_rungs: tuple = ("analytic",)  # its rate x noise grid on these rungs' records
    ident_engine_rungs: tuple = ("mujoco",)  # engine chains on a corner of its e x crown grid
    expected: str = ""
    notes: dict = field(default_factory=dict, compare=False)


PRESETS = {
    "default": Preset(
        "default", "central-leader",
        ("contact.duration=" + ",".join(f"{d:.3g}" for d in np.geomspace(2e-4, 2e-2, 8)),
         "crown_ratio=0:4:6"),
        ladder=False, speed=False, backends=("analytic", "soft", "beam"),
        engine_grid=("contact.duration=5e-4,5e-3", "crown_ratio=0,4"),
        map_metrics=("x_max", "energy_delivered", "crown_peak_acceleration"),
        map_value="step", identification=True,
        expected="about 25 s with 2 workers: 8 contact durations x 6 crown ratios on the "
                 "analytic, soft and beam backends, the engines' chains on 2 x 2 of them, "
                 "and the identification validation (4 e x 4 crown ratios x 3 rungs, MuJoCo's "
                 "chain on 2 x 2, 1-20 kHz x 0.5-2 % noise on exact SDOF records)"),
    "full": Preset(
        "full", "central-leader", ("restitution=0:0.9:10", "segments=1,2,4,8,16,32",
                                   "crown_ratio=0:4:9"),
        speed_dts=(1e-4, 5e-5, 2e-5, 1e-5, 5e-6), speed_durations=(2e-3, 1e-3, 5e-4),
        identification=True, ident_sampling_rungs=("analytic", "soft", "beam", *ENGINES),
        ident_engine_rungs=ENGINES,
        expected="about 1.5 CPU-hours: 45 minutes with 2 workers, 6 on 16 (measured on a "
                 "slice of the preset, 65 s of runs per (e, crown) pair; see "
                 "compare/sweep/study.py); resumable"),
}


def get_preset(name: str) -> Preset:
    try:
        return PRESETS[name]
    except KeyError:
        raise ParameterError(f"--preset {name!r}: allowed {', '.join(PRESETS)}") from None


def run_study(out, preset: str = "default", *, scenario=None, backends=None, workers=None,
              scheduler=None, progress=None, tolerance=None, grid=None,
              retry_failed: bool = False) -> dict:
    """Run (or resume) a preset's sweeps into ``out`` and write the study; returns the paths."""
    from .speed import speed_curves, speed_sweep

    p = get_preset(preset)
    t0 = time.perf_counter()
    out = make_out(out)
    scen = scenario or p.scenario
    engines = tuple(b for b in (backends or p.engines) if b in ENGINES)
    sweeps = {}
    if p.engine_grid:  # references on the fine grid, engines on a coarse one
        res = run_sweep(scen, list(grid or p.grid), out / "validity", backends=p.backends,
                        ladder=p.ladder, workers=workers, scheduler=scheduler,
                        progress=progress, retry_failed=retry_failed)
        sweeps["validity"] = res.out
        if engines:
            eng = run_sweep(scen, list(p.engine_grid), out / "engines",
                            backends=(*p.backends, *engines), ladder=p.ladder,
                            workers=workers, scheduler=scheduler, progress=progress,
                            retry_failed=retry_failed)
            sweeps["engines"] = eng.out
    else:
        res = run_sweep(scen, list(grid or p.grid), out / "validity",
                        backends=(*p.backends, *engines), ladder=p.ladder, workers=workers,
                        scheduler=scheduler, progress=progress, retry_failed=retry_failed)
        sweeps["validity"] = res.out
    speed = None
    if p.speed and engines:
        speed = speed_sweep(scen, out, engines=engines, dts=p.speed_dts,
                            durations=p.speed_durations, progress=progress)
        speed["curves"] = speed_curves(speed, out)
    ident_study = None
    if p.identification:
        from treeimpact.compare.ident_study import run_identification_study

        ident_study = run_identification_study(
            out, scen, workers=workers, progress=progress,
            sampling_rungs=p.ident_sampling_rungs, engine_rungs=p.ident_engine_rungs)
    return write_study(out, sweeps, speed=speed, tolerance=tolerance,
                       metrics=p.map_metrics, value=p.map_value, ident_study=ident_study,
                       title=f"Model-validity study ({p.name} preset)",
                       meta={"preset": p.name, "expected_run_time": p.expected,
                             "wall_s": time.perf_counter() - t0})


def _combined_table(out: Path, sweeps: dict, speed: dict | None):
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
    """A grid point as 'name = value, ...' (the table stores it as JSON pairs)."""
    try:
        pairs = json.loads(point) if isinstance(point, str) else point
        return ", ".join(f"{k} = {v:.3g}" if isinstance(v, float) else f"{k} = {v}"
                         for k, v in pairs)
    except (TypeError, ValueError):
        return str(point)


def _fmt_rel(v) -> str:
    return "n/a" if v is None or v != v else f"{v:+.1%}"


def write_study(out, sweeps: dict, *, speed: dict | None = None, tolerance=None,
                metrics=None, value: str = "rel", title: str = "Model-validity study",
                meta: dict | None = None, ident_study: dict | None = None) -> dict:
    """Draw the maps of finished sweeps (``{name: sweep dir}``) and write study.md,
    study.html, study.json and the combined results table into ``out``."""
    out = make_out(out)
    meta = dict(meta or {})
    table_path, table = _combined_table(out, sweeps, speed)
    validity, ident, specs = [], [], {}
    drawn = set()  # targets already mapped from an earlier (finer) sweep of the study
    for name, d in sweeps.items():
        df = read_table(d)
        specs[name] = json.loads((Path(d) / "sweep.json").read_text())
        prefix = "" if len(sweeps) == 1 or name == "validity" else f"{name}-"
        order = [t["id"] for t in specs[name].get("targets", [])]
        validity += validity_maps(df, out, tolerance=tolerance, prefix=f"{prefix}validity",
                                  order=order, value=value, skip=drawn,
                                  **({"metrics": metrics} if metrics else {}))
        ident += identification_maps(df, out, prefix=f"{prefix}identification", order=order,
                                     skip=drawn)
        drawn |= set(order)
    curves = (speed or {}).get("curves", [])
    status = table["status"].value_counts().to_dict() if len(table) else {}
    timings = {}
    if len(table):
        ok = table[table["status"] == "ok"].drop_duplicates(subset=["task"])
        for b, g in ok.groupby("backend"):
            timings[b] = {"runs": int(len(g)), "mean_wall_s": float(g["wall_s"].astype(float)
                                                                    .mean())}
    problems = []
    if len(table):
        bad = table[table["status"] != "ok"].drop_duplicates(subset=["target", "error"])
        problems = [{"sweep": r["sweep"], "target": r["target"], "status": r["status"],
                     "error": r["error"]} for _, r in bad.head(40).iterrows()]
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
    if ident_study is not None:
        summary["identification_validation"] = {
            "summary": ident_study["summary"], "sampling": ident_study.get("sampling", []),
            "figures": [f.name for f in ident_study["figures"]]}
    md = _markdown(summary, validity, ident, curves)
    (out / "study.md").write_text(md)
    (out / "study.json").write_text(json.dumps(_jsonable(summary), indent=2))
    (out / "study.html").write_text(_html(title, md))
    return {"md": out / "study.md", "html": out / "study.html", "json": out / "study.json",
            "table": table_path,
            "figures": [v["path"] for v in validity + ident if v["path"]]
            + [c["path"] for c in curves if c["path"]]}


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, float) and obj != obj:
        return None
    if isinstance(obj, Path):
        return str(obj)
    if hasattr(obj, "item"):
        return obj.item()
    return obj


def _ident_validation_md(iv) -> list[str]:
    """The identification validation (compare.ident_study) as markdown lines."""
    if not iv:
        return []
    from treeimpact.compare.ident_study import (
        ENGINE_CROWN_RATIOS,
        ENGINE_RESTITUTIONS,
        NOISE,
        RATE,
        RUNGS,
    )

    engines = [r for r in iv["summary"] if r not in RUNGS]
    corner = (f" (and of the {', '.join(engines)} hinged chain at e = "
              f"{', '.join(f'{e:g}' for e in ENGINE_RESTITUTIONS)} x crown ratio "
              f"{', '.join(f'{c:g}' for c in ENGINE_CROWN_RATIOS)})") if engines else ""
    L = ["## Identification validation: the full-record fit and the paper's procedure", "",
         f"Records of the {', '.join(RUNGS)} rungs over e x crown ratio{corner}, sampled at "
         f"{RATE / 1e3:g} kHz with {100 * NOISE:g} % noise (one seed), identified both ways; "
         "errors against the SDOF truth (M_T, K_T and b = C_T / (2 (M_T + m)), eq 42). "
         "`explained`: the fit's residual check says the 1-DOF model explains the record; "
         "`covered`: the fit's 95 % intervals (ranges where the record does not fix them) "
         "contain the truth (M_T, K_T, C_T). `one impact`: records the pendulum leaves "
         "after one impact fix omega_1, xi and V_1 = m (1 + e) u_1 / (M_T + m) but not M_T "
         "and e apart; the fit gives ranges there (not counted in `identified` or the 2 % "
         "column); the worst error with the pad's e given / with the pendulum's record y "
         "fitted too is shown.", "",
         "| rung | method | identified | all within 2 % (e <= 0.3) | worst M_T | worst K_T | "
         "worst b | one impact (worst: e given / y recorded) | covered | explained |",
         "|---|---|---|---|---|---|---|---|---|---|"]
    for rung, e in iv["summary"].items():
        for method in ("fit", "paper"):
            m = e[method]
            w = m["worst"]
            extra = (f"{m.get('not_fixed', 0)}"
                     + (f" ({_fmt_abs(m['known_e_worst'])} / "
                        f"{_fmt_abs(m.get('with_y_worst'))})" if m.get("not_fixed") else "")
                     + f" | {m['covered']:.0%} | {m['explained']:.0%}" if method == "fit"
                     else "- | - | -")
            L.append(f"| {rung} | {method} | {m['identified']} of {m['cases']} | "
                     f"{_fmt_abs(m['within_goal'])} | {_fmt_abs(w['M_T'])} | "
                     f"{_fmt_abs(w['K_T'])} | {_fmt_abs(w['b'])} | "
                     f"{extra} |")
    L.append("")
    if iv.get("sampling"):
        from treeimpact.compare.ident_study import SAMPLING_E, SAMPLING_SEEDS

        L += [f"How the sampling matters: records at e = {SAMPLING_E:g}, no crown "
              "(analytic: the exact SDOF), "
              f"{len(SAMPLING_SEEDS)} seeds per cell; the fit's worst |error| over M_T, K_T "
              "and b, how often its 95 % intervals cover the truth, and how often it says "
              "the 1-DOF model explains the record.", "",
              "| rung | rate | noise | fitted | worst error | intervals covering | explained |",
              "|---|---|---|---|---|---|---|"]
        for c in iv["sampling"]:
            L.append(f"| {c.get('rung')} | {c['rate_hz'] / 1e3:g} kHz | {100 * c['noise']:g} % "
                     f"| {c['fitted']} of {c['trials']} | {_fmt_abs(c['worst'])} | "
                     f"{_fmt_abs(c['covered'])} | {_fmt_abs(c.get('explained'))} |")
        L.append("")
    for f in iv["figures"]:
        L += [f"![{f}]({f})", ""]
    return L


def _fmt_abs(v) -> str:
    return "n/a" if v is None or v != v else f"{v:.1%}"


def _markdown(summary, validity, ident, curves) -> str:
    L = [f"# {summary['title']}", ""]
    for name, s in summary["sweeps"].items():
        L.append(f"- sweep `{name}`: scenario `{s['scenario']}`, grid "
                 + ", ".join(f"`{g}`" for g in s["grid"]))
    if summary.get("expected_run_time"):
        L.append(f"- expected run time of this preset: {summary['expected_run_time']}")
    if summary.get("wall_s") is not None:
        L.append(f"- this run took {summary['wall_s']:.1f} s (finished rows of an earlier "
                 f"run are reused)")
    L.append(f"- rows: {summary['rows']} ("
             + ", ".join(f"{k}: {v}" for k, v in sorted(summary["status"].items())) + ")")
    if summary["timings"]:
        L.append("- mean wall time per run: " + ", ".join(
            f"{b} {t['mean_wall_s']:.3g} s ({t['runs']} runs)"
            for b, t in summary["timings"].items()))
    versus = ("Relative discrepancy (target - analytic) / |analytic| of each metric from the "
              "paper's one-degree-of-freedom Newton-restitution model (eqs 12-35).") \
        if summary.get("map_value", "rel") == "rel" else (
            "Relative step of each target from the rung below it: soft vs analytic is the "
            "contact model, beam vs soft the 1-DOF assumption alone (the same pad), an "
            "engine's chain vs beam its discretisation and numerics.")
    L += ["", "## Validity maps", "", versus + " Tolerance "
          f"contour: {summary['tolerance'] if isinstance(summary['tolerance'], dict) else format(summary['tolerance'], '.0%')} "
          "(a study criterion: Table 1 prints M_T and K_T to two figures, and the paper's "
          "own identification is off by 15-30 % on exact records).", "",
          "Rung letters: " + "; ".join(f"**{k.letter}** {k.step}" for k in RungKind
                                        if k is not RungKind.NEWTON),
          ""]
    for v in validity:
        L.append(f"### {v['target']}")
        if v["path"] is not None:
            L += ["", f"![{v['target']}]({v['path'].name})", "", v["caption"], ""]
        L += ["| metric | within tolerance | worst | at | dominating rung (cells) |",
              "|---|---|---|---|---|"]
        for s in v["summary"]:
            dom = ", ".join(f"{k} {n}" for k, n in s["dominant"].items())
            L.append(f"| {s['metric']} | {s['within']:.0%} of {s['cells']} | "
                     f"{_fmt_rel(s['worst_rel'])} | {_fmt_point(s['worst_point'])} | {dom} |")
        L.append("")
    if not validity:
        L += ["No target other than the analytic reference produced values.", ""]
    L += ["## Identification maps", "",
          "The paper's identification procedure (eqs 39-48, as printed) run on each target's "
          "own displacement record, against the true M_T, K_T, xi and E of the scenario.", ""]
    for v in ident:
        L += [f"### {v['target']}", "", f"![identification {v['target']}]({v['path'].name})",
              "", v["caption"], "", "| parameter | cells | failed | best abs error | worst | at |",
              "|---|---|---|---|---|---|"]
        for s in v["summary"]:
            L.append(f"| {s['parameter']} | {s['cells']} | {s['failed']} | "
                     f"{s['best_abs_rel']:.1%} | {_fmt_rel(s['worst_rel'])} | "
                     f"{_fmt_point(s['worst_point'])} |")
        L.append("")
    L += _ident_validation_md(summary.get("identification_validation"))
    L += ["## Speed-accuracy curves", ""]
    for c in curves:
        if c["path"] is not None:
            L += [f"![speed {c['engine']}]({c['path'].name})", "", c["caption"], ""]
        else:
            L += [f"- {c['engine']}: no run succeeded ("
                  + "; ".join(sorted(set(c["points"]["error"].astype(str))))[:300] + ")", ""]
    for s in summary["speed"]["skipped"]:
        L.append(f"- skipped: {s['reason']}")
    if not curves and not summary["speed"]["skipped"]:
        L.append("No engine in this study.")
    L.append("")
    if summary["problems"]:
        L += ["## Rows without numbers", "", "| sweep | target | status | error |",
              "|---|---|---|---|"]
        for p in summary["problems"]:
            L.append(f"| {p['sweep']} | {p['target']} | {p['status']} | "
                     f"{str(p['error']).replace('|', '/')} |")
        L.append("")
    return "\n".join(L)


def _html(title: str, md: str) -> str:
    """A standalone page from the study's markdown (headings, lists, tables, images)."""
    style = ("body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}"
             "table{border-collapse:collapse;font-size:0.85em}td,th{border:1px solid #ccc;"
             "padding:2px 6px}code{font-size:0.85em}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
            f"</title><style>{style}</style></head><body>\n" + markdown_body(md)
            + "\n</body></html>\n")


def markdown_body(md: str, *, heading_shift: int = 0, image_src=None) -> str:
    """HTML of the study's markdown: the subset :func:`_markdown` writes (headings, lists,
    pipe tables, one image per line, inline code and bold). ``heading_shift`` demotes the
    headings (a report section nests them under its own); ``image_src(name)`` gives an
    image's src (the report links the study's PNGs relative to its own page)."""
    body = []
    lines = md.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("|"):
            rows = []
            while i < len(lines) and lines[i].startswith("|"):
                rows.append([c.strip() for c in lines[i].strip("|").split("|")])
                i += 1
            head, data = rows[0], [r for r in rows[2:]]
            body.append("<table><tr>" + "".join(f"<th>{_inline(c)}</th>" for c in head)
                        + "</tr>" + "".join("<tr>" + "".join(f"<td>{_inline(c)}</td>"
                                                             for c in r) + "</tr>" for r in data)
                        + "</table>")
            continue
        if line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            h = min(6, level + heading_shift)
            body.append(f"<h{h}>{_inline(line[level:].strip())}</h{h}>")
        elif line.startswith("!["):
            alt, src = line[2:].split("](", 1)
            src = src[:-1]
            if image_src is not None:
                src = image_src(src)
            body.append(f'<p><img src="{html.escape(src)}" alt="{html.escape(alt)}" '
                        f'style="max-width:100%"></p>')
        elif line.startswith("- "):
            items = []
            while i < len(lines) and lines[i].startswith("- "):
                items.append(f"<li>{_inline(lines[i][2:])}</li>")
                i += 1
            body.append("<ul>" + "".join(items) + "</ul>")
            continue
        elif line.strip():
            body.append(f"<p>{_inline(line)}</p>")
        i += 1
    return "\n".join(body)


def _inline(text: str) -> str:
    import re

    t = html.escape(text)
    t = re.sub(r"`([^`]*)`", r"<code>\1</code>", t)
    t = re.sub(r"\*\*([^*]*)\*\*", r"<b>\1</b>", t)
    return t
