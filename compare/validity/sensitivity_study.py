"""The sensitivity part of a model-validity study (compare.studies.sensitivity): one sweep per tree,
run on the pool of the study's validity sweep, then analysed and drawn. Design notes:
docs/sensitivity.md."""

from __future__ import annotations

from pathlib import Path

from treeimpact.analytic.model.scenario import shipped_scenarios
from treeimpact.compare.runs import resolve_scenario
from treeimpact.compare.studies.sensitivity import (
    analyse,
    free_inputs,
    inputs_of,
    measured_inputs,
    sensitivity_sweep,
)
from treeimpact.compare.studies.sobol import analyse_sobol, sobol_sweep

from ..sweep.maps import sensitivity_figure
from ..sweep.run import run_sweeps


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
        trees[s.name] = analyse(done[i].table, sens["trajectories"], names=free_inputs(s),
                                held={n: own[n] for n in measured_inputs(s)})
        if sens.get("sobol"):
            trees[s.name]["sobol"] = analyse_sobol(done[count + i].table, sens["sobol"],
                                                   names=free_inputs(s))
    path = sensitivity_figure(trees, Path(out) / "sensitivity.png")
    return {"trajectories": sens["trajectories"], "crossings": sens["crossings"],
            "sobol": sens.get("sobol", 0), "trees": trees,
            "figure": path.name if path else None}


def run_sensitivity(out, trajectories: int, *, crossings: bool = False, scenarios=None,
                    workers=None, scheduler=None, progress=None,
                    retry_failed: bool = False, sobol: int = 0) -> dict:
    """The sensitivity study alone into ``out`` (:func:`sensitivity_specs` of
    ``trajectories``, ``crossings``, ``scenarios`` and ``sobol`` on one pool, then
    :func:`sensitivity_result`); ``workers``, ``scheduler``, ``progress`` and
    ``retry_failed`` as :func:`compare.sweep.run.run_sweeps`."""
    sens = sensitivity_specs(out, trajectories, crossings=crossings, scenarios=scenarios,
                             sobol=sobol)
    done = run_sweeps(sens["specs"], workers=workers, scheduler=scheduler,
                      progress=progress, retry_failed=retry_failed)
    return sensitivity_result(out, sens, done)
