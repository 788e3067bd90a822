"""The sensitivity part of a model-validity study (compare.studies.sensitivity): one sweep per tree,
run on the pool of the study's validity sweep, then analysed and drawn. Design notes:
docs/sensitivity.md."""

from __future__ import annotations

from pathlib import Path

from treeimpact.analytic.model.scenario import shipped_scenarios
from treeimpact.compare.runs.cache import resolve_scenario
from treeimpact.compare.studies.sensitivity import analyse, sensitivity_sweep
from treeimpact.compare.studies.sobol import analyse_sobol, sobol_sweep
from treeimpact.compare.studies.study_inputs import (
    free_inputs,
    inputs_of,
    measured_inputs,
    ranges_of,
)

from ...studies.sweep.maps import sensitivity_figure
from ...studies.sweep.run import run_sweeps


def sensitivity_specs(out, trajectories: int, *, crossings: bool = False,
                      scenarios=None, sobol: int = 0) -> dict:
    """The sensitivity study (compare.studies.sensitivity) of each tree of ``scenarios`` (default:
    every shipped one) as sweeps into ``out/sensitivity/``, each tree's measured inputs
    held at its file's values: the Morris screen, then with ``sobol`` (base samples N, a
    power of two; 0: none) the Sobol design (compare.studies.sobol) into
    ``out/sensitivity-sobol/``: {trees, specs (Morris, then Sobol), trajectories,
    crossings, sobol}."""
    scens = [resolve_scenario(s) for s in (scenarios or shipped_scenarios())]
    specs = [sensitivity_sweep(s, Path(out) / "sensitivity" / s.name, trajectories,
                               crossings=crossings) for s in scens]
    if sobol:
        specs += [sobol_sweep(s, Path(out) / "sensitivity-sobol" / s.name, sobol)
                  for s in scens]
    return {"trees": scens, "trajectories": trajectories, "crossings": crossings,
            "sobol": sobol, "specs": specs}


def sensitivity_result(out, sens: dict, done: list) -> dict:
    """The analysis of the finished sweeps ``done`` of :func:`sensitivity_specs` ``sens``
    and its figure (written into ``out``): {trajectories, crossings, trees: {name:
    analysis}, figure}."""
    trees = {}
    count = len(sens["trees"])
    for i, s in enumerate(sens["trees"]):
        own = inputs_of(s)
        ranges = ranges_of(s)
        trees[s.name] = analyse(done[i].table, sens["trajectories"], names=free_inputs(s),
                                held={n: own[n] for n in measured_inputs(s)}, ranges=ranges)
        if sens.get("sobol"):
            trees[s.name]["sobol"] = analyse_sobol(done[count + i].table, sens["sobol"],
                                                   names=free_inputs(s), ranges=ranges)
        said(trees[s.name])
    path = sensitivity_figure(trees, Path(out) / "sensitivity.png")
    return {"trajectories": sens["trajectories"], "crossings": sens["crossings"],
            "sobol": sens.get("sobol", 0), "trees": trees,
            "figure": path.name if path else None, "points": point_counts(trees)}


#: The failed points a page lists per design (study.json keeps them all, up to
#: compare.studies.study_points.MAX_LISTED).
SHOWN = 3


def said(tree: dict) -> None:
    """The page's words on one tree's designs (its :func:`analyse` with its ``sobol``),
    added to them: ``ranges_text`` (the inputs whose range on this tree differs from the
    registry's, with the rule; '' when none), and per design ``points_text`` (how many of
    its points failed and what its indices rest on; '' when none failed) and
    ``failed_shown`` (the first SHOWN failed points' lines). Changes ``tree`` in place."""
    reasons: dict = {}  # why -> the inputs it narrowed, each with its two ranges
    for n, v in tree["inputs"].items():
        if v.get("clipped"):
            unit = "" if v["unit"] == "1" else f" {v['unit']}"
            reasons.setdefault(v["clipped"], []).append(
                f"{n} {v['low']:.4g} to {v['high']:.4g}{unit} (registry "
                f"{v['registry'][0]:.4g} to {v['registry'][1]:.4g})")
    tree["ranges_text"] = ("Ranges on this tree, narrowed from the registry's so that every "
                           "point is a valid tree with its measured M_T and K_T: "
                           + "; ".join(f"{', '.join(names)}: {why}"
                                       for why, names in reasons.items()) + ".") \
        if reasons else ""
    for part, unit, used, of, spread in (
            (tree, "trajectories", "trajectories_used", "trajectories",
             "the lowest and highest on the {} points that ran"),
            (tree.get("sobol"), "Saltelli blocks", "blocks_used", "n",
             "the lowest and highest on their points")):
        if not part:
            continue
        part["failed_shown"] = [f["text"] for f in part["failed_points"][:SHOWN]]
        if not part["failed"]:
            part["points_text"] = ""
            continue
        rest = (f"the indices and their intervals rest on {part[used]} of the {part[of]} "
                f"{unit}, the complete ones (one with a failed point is dropped whole, never "
                f"imputed), {spread.format(part['evaluations'])}") if part[used] else \
            f"no {_one(unit)} of {part[of]} is complete: no indices"
        part["points_text"] = f"{part['failed']} of {part['points']} points failed; {rest}."


def _one(unit: str) -> str:
    """The singular of 'trajectories' or 'Saltelli blocks'."""
    return unit[:-3] + "y" if unit.endswith("ies") else unit[:-1]


def point_counts(trees: dict) -> dict:
    """How many of the study's points ran, over its trees' designs ``trees`` (tree ->
    :func:`analyse` with its ``sobol``, worded by :func:`said`): {points, failed, ran,
    lines}: ``lines`` one per design with a failed point, its ``points_text`` and the
    first failed point (index, inputs, reason): what stderr says."""
    points = failed = 0
    lines = []
    for name, tree in trees.items():
        for what, part in (("Morris", tree), ("Sobol", tree.get("sobol"))):
            if not part:
                continue
            points += part["points"]
            failed += part["failed"]
            if part["failed"]:
                lines.append(f"sensitivity {name} ({what}): {part['points_text']} The first: "
                             f"{part['failed_points'][0]['text']}")
    return {"points": points, "failed": failed, "ran": points - failed, "lines": lines}


def run_sensitivity(out, trajectories: int, *, crossings: bool = False, scenarios=None,
                    workers=None, scheduler=None, progress=None,
                    retry_failed: bool = False, sobol: int = 0) -> dict:
    """The sensitivity study alone into ``out`` (:func:`sensitivity_specs` of
    ``trajectories``, ``crossings``, ``scenarios`` and ``sobol`` on one pool, then
    :func:`sensitivity_result`); ``workers``, ``scheduler``, ``progress`` and
    ``retry_failed`` as :func:`compare.studies.sweep.run.run_sweeps`."""
    sens = sensitivity_specs(out, trajectories, crossings=crossings, scenarios=scenarios,
                             sobol=sobol)
    done = run_sweeps(sens["specs"], workers=workers, scheduler=scheduler,
                      progress=progress, retry_failed=retry_failed)
    return sensitivity_result(out, sens, done)
