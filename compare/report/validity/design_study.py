"""The design study (``treeimpact sweep --preset design``, ``report --with-study design``,
the API's ``design_map``): the maps of compare.studies.design for one tree, one sweep per
pair of inputs and one over the family of trunk diameters, all on one pool (resumable,
Dask with ``scheduler``), then the contour figures, the sentences of
compare.studies.design_words and the page. Writes into ``out``: design.json (every number),
design.md, design.html, design-*.png, one sweep directory per map. Design notes:
docs/design-map.md."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

from treeimpact.analytic.errors import NotAchieved, ParameterError, SimulationDiverged, one_line
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.scenario import shipped_scenarios
from treeimpact.analytic.results import check_plausible, json_text, to_jsonable

from ...runs.cache import resolve_scenario
from ...studies.design import (
    DIAMETER_FACTORS,
    HELD,
    INPUTS,
    LEVELS,
    PAIRS,
    QUANTITIES,
    Kind,
    check_grid_specs,
    check_operating_point,
    check_ranges,
    design_cell,
    design_spec,
    map_of,
    map_ranges,
    operating_point,
    pair_grid,
)
from ...studies.design_choice import cell_point, choice_text, designer_choice
from ...studies.design_engines import spot_checks
from ...studies.design_words import (
    along,
    nearest_within,
    sentence_along,
    sentence_at_point,
    sentence_nearest,
    shown,
)
from ...studies.small_e import exact_run
from ...studies.sweep.design_maps import Axis, Point, draw_pair
from ...studies.sweep.journal import make_out
from ...studies.sweep.run import run_sweeps
from .presets import Preset, register

#: The quantities each pair's figure draws, and the sentences read off it:
#: (quantity, tolerance) along the pair's first input (True) or second (False).
PANELS = {PAIRS[0]: ("x_max", "energy_delivered", "crown_peak_acceleration"),
          PAIRS[1]: ("x_max", "energy_delivered", "crown_peak_acceleration"),
          PAIRS[2]: ("x_max", "eq57_energy_loss", "identification_M_T", "identification_K_T")}
READINGS = {PAIRS[0]: (("x_max", 0.05, True), ("energy_delivered", 0.20, True)),
            PAIRS[1]: (("x_max", 0.05, False), ("energy_delivered", 0.20, False)),
            PAIRS[2]: (("eq57_energy_loss", 0.05, False), ("identification_M_T", 0.05, False),
                       ("x_max", 0.05, False))}
#: The designer's target on the 1-DOF maps (rule 3): x_max within 5 %, energy within 20 %.
TARGET = {"x_max": 0.05, "energy_delivered": 0.20}
#: The map's points per input when none is given (30 x 30 = 900 cells a pair).
COUNT = 30


def _name(pair) -> str:
    return f"{pair[0]}-{pair[1]}"


def tree_cell(scen) -> tuple:
    """The cell at the tree ``scen`` itself (its own a/l, m/M_T, pad and e), computed directly:
    ({quantity: relative gap or error}, None), or ({quantity: NaN}, the one-line reason)
    when its exact run has no numbers to report (a t_end too short for the impact: the
    check a map's cell passes, analytic.results.check_plausible)."""
    run, s = exact_run(scen, scen.contact.restitution)
    try:
        check_plausible(run)
    except (ParameterError, SimulationDiverged) as exc:
        return {q: math.nan for q in QUANTITIES}, one_line(exc)
    return {k.split(".", 1)[1]: v for k, v in design_cell(run, s).items()}, None


def _typed(scenario, scen) -> str:
    """The tree as a refusal names it: ``--scenario`` and what was given (a name or path;
    a Scenario by its name; the API names the keyword)."""
    return f"--scenario {str(scenario) if isinstance(scenario, (str, Path)) else scen.name!r}"


def _map_specs(out: Path, scen, count: int, ranges: dict, grid, typed: str) -> list:
    """The study's sweeps: one map per pair, the family of trunk diameters and the
    user's ``grid`` (if any); the study's own grids named in refusals as the map of
    ``typed`` (the tree as given), not as specs nobody typed."""
    here = operating_point(scen)
    specs = []
    for p in PAIRS:
        held = ", ".join(f"{INPUTS[n].label} {shown(n, here[n])}" for n in INPUTS if n not in p)
        specs.append(design_spec(scen, pair_grid(scen, p, count, ranges), out / _name(p),
                                 label=f"{typed} (its {INPUTS[p[0]].label} x "
                                       f"{INPUTS[p[1]].label} map at the tree's {held})"))
    d = scen.trunk.diameter
    specs.append(design_spec(scen, ["trunk.diameter=" + ",".join(
        repr(float(f"{d * f:.6g}")) for f in DIAMETER_FACTORS)], out / "diameter",
        label=f"{typed} (its family of trunk diameters "
              f"{', '.join(f'{f:g}' for f in DIAMETER_FACTORS)} d)"))
    if grid:
        specs.append(design_spec(scen, grid, out / "grid"))
    return specs


def check_cells_ran(results, out) -> None:
    """NotAchieved (one line: the cells, their outcomes, the first reason and the study's
    folder ``out``, where the rows are kept) when no cell of the study's sweeps ``results``
    has numbers: nothing to map or to put in words."""
    tables = [r.table for r in results if len(r.table)]
    if any((t["status"] == "ok").any() for t in tables):
        return
    counts: dict = {}
    reasons = []
    for t in tables:
        for status, n in t["status"].value_counts().items():
            counts[status] = counts.get(status, 0) + int(n)
        # the scenario's t_end, not a flag of this command
        reasons += [str(e).replace("--t-end", "t_end") for e in t["error"]
                    if isinstance(e, str) and e]
    n = sum(counts.values())
    raise NotAchieved(f"design: no cell of the maps has numbers ({n} cells: "
                      + ", ".join(f"{v} {k}" for k, v in sorted(counts.items()))
                      + (f"; the first: {reasons[0]}" if reasons else "")
                      + f"); no map or sentence written, the rows kept in {out}")


def _points(scen, pair, shipped) -> list:
    out = []
    for name, s in shipped.items():
        here = operating_point(s)
        out.append(Point(name, *(here[p] * INPUTS[p].show for p in pair)))
    here = operating_point(scen)
    out.append(Point(f"{scen.name} (this tree)", *(here[p] * INPUTS[p].show for p in pair),
                     own=True))
    return out


def _axis(name, values) -> Axis:
    inp = INPUTS[name]
    unit = inp.shown_unit or inp.unit
    return Axis(tuple(v * inp.show for v in values), f"{inp.label} ({unit})",
                inp.scale.value == "log")


def pair_sentences(x, y, maps: dict, pair, here: dict, cell: dict) -> list:
    """The sentences of the map over ``pair`` (``maps`` {quantity: z, z[j, i] at y[j],
    x[i]}) at the tree's operating point ``here``: :data:`READINGS` along an input, each
    resting on the map's line and the tree's own ``cell`` ({quantity: gap}, computed at the
    tree), and rule 3's nearest choice within :data:`TARGET` on a 1-DOF map; dicts with
    the text, the rule and what it read."""
    sentences = []
    for q, tol, first in READINGS[pair]:
        own = cell.get(q)
        if first:
            text = sentence_along(x, y, maps[q], pair, here, q, tol, own)
            found = along(x, y, maps[q], pair, here, tol, own)[0]
        else:
            flip = (pair[1], pair[0])
            text = sentence_along(y, x, maps[q].T, flip, here, q, tol, own)
            found = along(y, x, maps[q].T, flip, here, tol, own)[0]
        sentences.append({"text": text, "rule": "along", "quantity": q, "tolerance": tol,
                          "along": pair[0] if first else pair[1], "within": found})
    if all(QUANTITIES[q].kind is Kind.ONE_DOF for q in PANELS[pair]):
        sentences.append({"text": sentence_nearest(x, y, maps, TARGET, pair, here),
                          "rule": "nearest", "tolerances": TARGET,
                          "at": nearest_within(x, y, maps, TARGET, pair, here)})
    return sentences


def _recommend(scen, sentences: list, pair, here: dict) -> None:
    """The nearest choice of ``sentences`` (if a cell was found) in the designer's units
    (compare.studies.design_choice), its ``choice`` and its words added to the sentence."""
    for s in sentences:
        if s["rule"] == "nearest" and s["at"] is not None:
            s["choice"] = designer_choice(scen, cell_point(here, pair, s["at"]))
            s["text"] += " " + choice_text(s["choice"])


def _pair_part(out: Path, scen, pair, table, shipped, cell: dict) -> dict:
    here = operating_point(scen)
    maps = {}
    for q in QUANTITIES:
        x, y, z = map_of(table, pair, q)
        maps[q] = z
    sentences = pair_sentences(x, y, maps, pair, here, cell)
    _recommend(scen, sentences, pair, here)
    figure = f"design-{_name(pair)}.png"
    what = "1-DOF gaps and small-e errors" if any(
        QUANTITIES[q].kind is Kind.SMALL_E for q in PANELS[pair]) else "1-DOF gaps"
    title = f"{scen.name}: {what} over {INPUTS[pair[0]].label} and {INPUTS[pair[1]].label}"
    held = [f"{INPUTS[n].label} {shown(n, here[n])}" for n in INPUTS if n not in pair]
    draw_pair(out / figure, _axis(pair[0], x), _axis(pair[1], y),
              {f"{QUANTITIES[q].label} ({QUANTITIES[q].kind.value})": maps[q]
               for q in PANELS[pair]}, _points(scen, pair, shipped),
              title + f"\n(held at the tree's {', '.join(held)})")
    return {"pair": list(pair), "x": list(x), "y": list(y), "figure": figure,
            "held_at": {n: here[n] for n in INPUTS if n not in pair},
            "maps": {q: maps[q] for q in QUANTITIES}, "sentences": sentences}


def _family(table) -> list:
    rows = table[table["status"] == "ok"].sort_values("trunk.diameter")
    return [{"diameter": float(r["trunk.diameter"])} |
            {q: float(r[f"design.{q}"]) for q in QUANTITIES} for _, r in rows.iterrows()]


def _cost(results, wall_s: float, workers) -> dict:
    """What the maps cost: cells (this run's and all), the sweeps' ``wall_s`` (s) on
    ``workers`` processes, and per cell computed by this run of ``results`` the wall time
    times the workers (CPU-seconds a cell, every rung and the pool included)."""
    n = workers if workers else (os.cpu_count() or 1) if workers is None else 1
    cells = sum(len(r.table) for r in results)
    made = sum(r.rows_written for r in results)  # this run's; the rest found done
    return {"cells": cells, "cells_computed": made, "wall_s": wall_s, "workers": n,
            "cpu_s_per_cell": wall_s * n / made if made else None}


def check_keywords(out, scenario, engines) -> None:
    """TypeError naming the keyword of :func:`run_design_study` (and the API's design_map)
    given a value of the wrong type: ``out`` a path, ``scenario`` a Scenario, name or
    path, ``engines`` True or False."""
    if not isinstance(out, (str, Path)):
        raise TypeError(f"out: expected a directory (str or pathlib.Path), got {out!r}")
    if not isinstance(scenario, (Scenario, str, Path)):
        raise TypeError(f"scenario: expected a Scenario, a shipped scenario's name or a TOML "
                        f"path, got {scenario!r} ({type(scenario).__name__})")
    if not isinstance(engines, bool):
        raise TypeError(f"engines: expected True or False, got {engines!r}")


def run_design_study(out, scenario="central-leader", *, count: int = COUNT, ranges=None,
                     workers=None, scheduler=None, progress=None, grid=None,
                     retry_failed: bool = False, engines: bool = False) -> dict:
    """Run (or resume) the design study of ``scenario`` into ``out``; returns the paths
    ({"json", "md", "html", "table", "figures"}). ``count``: values per input of each pair's
    map; ``ranges``: {input: (low, high)} replacing the default ranges (ParameterError if
    outside the allowed); ``grid``: ``--grid`` specs of one more sweep over the design
    inputs (the four-input grid), its cost recorded; ``workers``, ``scheduler``,
    ``progress``, ``retry_failed`` as compare.studies.sweep.run.run_sweeps; ``engines``: the
    engines' spot checks too (compare.studies.design_engines)."""
    check_keywords(out, scenario, engines)
    check_ranges({} if ranges is None else ranges)
    ranges = dict(ranges or {})
    if grid:
        check_grid_specs(grid)
    t0 = time.perf_counter()
    scen = resolve_scenario(scenario)
    check_operating_point(scen, _typed(scenario, scen))
    out = make_out(out)
    specs = _map_specs(out, scen, count, ranges, grid, _typed(scenario, scen))
    results = run_sweeps(specs, workers=workers, scheduler=scheduler, progress=progress,
                         retry_failed=retry_failed)
    check_cells_ran(results, out)
    maps_wall = time.perf_counter() - t0
    shipped = {n: resolve_scenario(n) for n in shipped_scenarios()}
    cell, problem = tree_cell(scen)
    pairs = [_pair_part(out, scen, p, r.table, shipped, cell)
             for p, r in zip(PAIRS, results)]
    here = operating_point(scen)
    spans = map_ranges(scen, ranges)
    data = {"title": f"Design map: {scen.name}", "tree": scen.name,
            "operating_point": here, "cell": cell, "levels": list(LEVELS),
            "inputs": {n: {"unit": i.unit, "low": spans[n][0], "high": spans[n][1],
                           "allowed": list(i.allowed), "label": i.label, "why": i.why,
                           "scale": i.scale.value} for n, i in INPUTS.items()},
            "held": HELD, "count": count, "ranges": ranges,
            "quantities": {q: {"label": v.label, "kind": v.kind.value}
                           for q, v in QUANTITIES.items()},
            "at_point": sentence_at_point(here, cell, ("x_max", "energy_delivered",
                                                      "crown_peak_acceleration"), problem),
            "shipped": {n: operating_point(s) for n, s in shipped.items()},
            "pairs": pairs, "family": _family(results[len(PAIRS)].table),
            "cost": _cost(results, maps_wall, workers),
            "wall_s": time.perf_counter() - t0}
    if problem is None:  # the tree as it is, in the designer's units
        own = designer_choice(scen, cell_point(here, PAIRS[0], (here[PAIRS[0][0]],
                                                                here[PAIRS[0][1]])))
        data["choice_at_point"] = own | {"text": choice_text(own, "The tree as it is")}
    if engines:
        p = pairs[1]
        data["spot_checks"] = spot_checks(scen, p["x"], p["y"], p["maps"]["x_max"],
                                          tuple(p["pair"]), here, LEVELS[0], workers=workers)
    if grid:
        g = results[-1]
        data["grid"] = {"specs": list(grid), "cells": len(g.table)}
    return write_design(out, to_jsonable(data))


def write_design(out, data: dict) -> dict:
    """Write design.json, design.md and design.html of the study ``data`` into ``out``;
    returns the paths."""
    # lazy: +105 ms at import otherwise (jinja2, numpy),
    # which this module's other callers do not need
    from treeimpact.compare.report.base import environment

    out = Path(out)
    (out / "design.json").write_text(json_text(data, indent=1), encoding="utf-8")
    env = environment()
    md = env.get_template("design_body.md.j2").render(d=data, level=1, image=lambda n: n)
    html = env.get_template("design_page.html.j2").render(d=data, level=1, image=lambda n: n)
    (out / "design.md").write_text(md, encoding="utf-8")
    (out / "design.html").write_text(html, encoding="utf-8")
    return {"json": out / "design.json", "md": out / "design.md", "html": out / "design.html",
            "table": out / "design.json",
            "figures": [out / p["figure"] for p in data["pairs"]]}


#: The design map as ``treeimpact sweep --preset design`` and ``report --with-study design``.
register(Preset("design", "central-leader", (), run=run_design_study, folder="design",
                expected="about 20 s alone with 2 workers: 3 maps of 30 x 30 cells and 5 "
                         "trunk diameters",
                help="design (the design map of --scenario: a/l, m/M_T, contact duration, e; "
                     "docs/design-map.md) about 20 s alone"))
