"""The sensitivity part of a model-validity study (compare.studies.sensitivity): one sweep per tree,
run on the pool of the study's validity sweep, then analysed and drawn. Design notes:
docs/sensitivity.md."""

from __future__ import annotations

from pathlib import Path

from ..sweep.run import run_sweeps


def sensitivity_specs(out, trajectories: int, *, crossings: bool = False,
                      scenarios=None) -> dict:
    """The sensitivity study (compare.studies.sensitivity) of each tree of ``scenarios`` (default:
    every shipped one) as sweeps into ``out/sensitivity/``, each tree's measured inputs
    held at its file's values: {trees, specs, trajectories, crossings}."""
    from treeimpact.analytic.model.scenario import shipped_scenarios
    from treeimpact.compare.runs import resolve_scenario
    from treeimpact.compare.studies.sensitivity import sensitivity_sweep

    scens = [resolve_scenario(s) for s in (scenarios or shipped_scenarios())]
    return {"trees": scens, "trajectories": trajectories, "crossings": crossings,
            "specs": [sensitivity_sweep(s, Path(out) / "sensitivity" / s.name, trajectories,
                                        crossings=crossings) for s in scens]}


def sensitivity_result(out, sens: dict, done: list) -> dict:
    """The analysis of the finished sweeps ``done`` of :func:`sensitivity_specs` ``sens``
    and its figure (written into ``out``): {trajectories, crossings, trees: {name:
    analysis}, figure}."""
    from treeimpact.compare.studies.sensitivity import (
        analyse,
        free_inputs,
        inputs_of,
        measured_inputs,
    )

    from ..sweep.maps import sensitivity_figure

    trees = {}
    for s, r in zip(sens["trees"], done):
        own = inputs_of(s)
        trees[s.name] = analyse(r.table, sens["trajectories"], names=free_inputs(s),
                                held={n: own[n] for n in measured_inputs(s)})
    path = sensitivity_figure(trees, Path(out) / "sensitivity.png")
    return {"trajectories": sens["trajectories"], "crossings": sens["crossings"],
            "trees": trees, "figure": path.name if path else None}


def run_sensitivity(out, trajectories: int, *, crossings: bool = False, scenarios=None,
                    workers=None, scheduler=None, progress=None,
                    retry_failed: bool = False) -> dict:
    """The sensitivity study alone into ``out`` (:func:`sensitivity_specs` of
    ``trajectories``, ``crossings`` and ``scenarios`` on one pool, then
    :func:`sensitivity_result`); ``workers``, ``scheduler``, ``progress`` and
    ``retry_failed`` as :func:`compare.sweep.run.run_sweeps`."""
    sens = sensitivity_specs(out, trajectories, crossings=crossings, scenarios=scenarios)
    done = run_sweeps(sens["specs"], workers=workers, scheduler=scheduler,
                      progress=progress, retry_failed=retry_failed)
    return sensitivity_result(out, sens, done)
