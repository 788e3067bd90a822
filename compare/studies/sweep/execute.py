"""One sweep task run: the backend called once for every row whose inputs are identical, its
outcome as the table's columns (the run's metrics and model, the paper's identification on
its record) or as an analysis gives them (``module:function``), never an exception.

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

import importlib
import json
import math
import os
import socket
from dataclasses import dataclass, field

from treeimpact.analytic.errors import one_line
from treeimpact.analytic.metrics import METRIC_KEYS
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.compare.runs.cache import DIVERGED, FAILED, INVALID, OK, attempt, failure
from treeimpact.compare.tree.identification import identify_rung

#: The model quantities of a run kept as the table's ``model.*`` columns (SI; the run's
#: ``model`` dict).
MODEL_KEYS = ("M_T", "C_T", "K_T", "m", "k", "restitution", "u1", "segments", "dt",
              "contact_stiffness", "contact_damping", "contact_reduced_mass",
              "pad_damping_ratio")
#: The identified quantities kept as ``id.*`` and their truth as ``truth.*`` (SI;
#: compare.tree.identification.IDENT_METRICS).
IDENT_KEYS = ("M_T", "K_T", "pair_damping_ratio", "E")


def load_analysis(ref: str):
    """The analysis function ``ref`` names (``module:function``, the module imported):
    ``fn(result, scenario, record) -> {column: value}`` with its ``columns`` (a tuple) as an
    attribute."""
    module, name = ref.split(":")
    return getattr(importlib.import_module(module), name)


@dataclass
class Task:
    """One backend call, shared by every (point, target) row whose inputs are identical;
    ``analysis`` (``module:function``) runs on its result once per distinct record
    parameters of the rows (grid axes ``record.*``) instead of the standard columns."""

    key: str
    scenario: Scenario
    backend: object  # compare.runs.backends.Backend (pickled whole, so a worker needs no registry)
    options: dict
    identify: bool
    analysis: str | None = None
    part: int = 0  # the sweep of run_sweeps it belongs to
    rows: list = field(default_factory=list)  # (point, point key, target, record parameters)
    run: str = ""  # the key of its backend call alone (the same for the tasks that repeat
    #                one run per record, compare.studies.sweep.plan; "": its own)


def _identify(result, scenario: Scenario) -> dict:
    """The paper's procedure on the run's record (compare.tree.identification.identify_rung) as the
    sweep's id.* and truth.* columns, or id_error."""
    ident = identify_rung(result, scenario)
    out = {f"truth.{k}": v for k, v in ident.truth.items()}
    if not ident.ok:
        out["id_error"] = ident.reason
        return out
    out.update({f"id.{k}": float(v) for k, v in ident.values.items()})
    return out


#: The last backend call this process made, (Task.run, its Run): the tasks that repeat one
#: run per record (compare.studies.sweep.plan) come in a row in a worker call, and the run is a
#: deterministic function of its key (scenario digest, backend, options), so the next one
#: reuses it instead of repeating it (the Sobol design's 6144 rows made 6144 identical runs
#: of the base tree, about 1 ms each, whose result their analysis does not read).
_LAST_RUN: list = [None, None]


def _run(task: Task):
    """The task's backend run (compare.runs.cache.attempt), reused from :data:`_LAST_RUN` when the
    previous task of this process made the same call (``task.run``)."""
    if task.run and _LAST_RUN[0] == task.run:
        return _LAST_RUN[1]
    done = attempt(task.backend, task.scenario, task.options)
    _LAST_RUN[:] = [task.run or None, done]
    return done


def execute(task: Task) -> list[dict]:
    """Run one task: the outcome of each of its rows; never raises for a failing run (the
    error is the outcome)."""
    done = _run(task)
    out = {"status": done.status, "error": done.reason, "t_end": task.scenario.t_end,
           "worker": f"{socket.gethostname()}:{os.getpid()}", "wall_s": done.wall_s}
    result = done.result
    if done.status == OK:
        infinite = [k for k in METRIC_KEYS if math.isinf(_num(result.metrics.get(k)))]
        if infinite:  # a run that returned instead of raising: a divergence, not numbers
            out.update(status=DIVERGED, error=f"diverged: infinite {', '.join(infinite)}")
    if out["status"] != OK:
        return [out] * len(task.rows)
    if task.analysis is None:
        out.update({k: _num(result.metrics.get(k)) for k in METRIC_KEYS})
        model = result.model or {}
        out.update({f"model.{k}": _num(model.get(k)) for k in MODEL_KEYS})
        if task.identify:
            out.update(_identify(result, task.scenario))
        return [out] * len(task.rows)
    analyse = load_analysis(task.analysis)
    made: dict = {}
    outcomes = []
    for *_, record in task.rows:  # one analysis per distinct record parameters
        key = json.dumps(record, sort_keys=True)
        if key not in made:
            made[key] = out | _analysed(analyse, result, task.scenario, record)
        outcomes.append(made[key])
    return outcomes


def _analysed(analyse, result, scenario: Scenario, record: dict) -> dict:
    """``analyse(result, scenario, record)``'s columns, or the point's outcome when it
    raises (never the exception: one point does not end its sweep): INVALID for a
    ParameterError (the point's inputs make no valid tree), OUTSIDE, DIVERGED, else FAILED,
    each with its one-line reason (the row keeps the point's ``input.*`` values)."""
    try:
        return analyse(result, scenario, record)
    except Exception as exc:  # noqa: BLE001 - recorded and shown with the point
        status, reason = failure(exc, INVALID)
    return {"status": status, "error": reason}


def run_chunk(tasks: list) -> list:
    """Worker entry point: :func:`execute` on each of ``tasks`` (:class:`Task`, one worker
    call as compare.studies.sweep.cost.chunks groups them); each task's row outcomes, in order."""
    return [execute(t) for t in tasks]


def _num(v):
    if v is None:
        return math.nan
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def died(task: Task, exc: BaseException) -> list[dict]:
    """The outcome of each row of ``task`` when the worker process running it died
    (``exc``): FAILED with the reason, to rerun with ``--retry-failed``."""
    return [{"status": FAILED, "t_end": task.scenario.t_end, "wall_s": math.nan,
             "error": f"worker process died running this point ({type(exc).__name__}: "
                      f"{one_line(exc)}); rerun with --retry-failed"}] * len(task.rows)
