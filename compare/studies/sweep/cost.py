"""The sweep's cost model: how long a run of each kind takes (the registry's estimate), and
the tasks grouped into worker calls by it: short runs together up to a budget a call, the
longest calls first.

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

from treeimpact.compare.runs.backends import get_backend

#: Seconds one record's analysis takes (a full-record fit of compare.studies.ident_records, median
#: 0.5 s, docs/identification.md): a run cheaper than this is repeated per record.
ANALYSIS_COST = 0.5

#: Seconds of estimated work per worker call. A call costs scheduling: measured on the 2-core
#: VM, 4 ms a call through a Dask LocalCluster (0.02 s calls ran at 89 % of two cores, 0.1 s
#: calls at 96 %) and well under 1 ms through the process pool; so short runs are grouped.
#: An interrupted sweep loses at most about this much finished work per worker (a run
#: longer than this is a call of its own).
CALL_BUDGET = 1.0


def _cost_class(task) -> tuple:
    trunk = task.options.get("trunk")
    return (task.backend.name, trunk if trunk == "sdof" else None)


def _run_cost(cost_class: tuple) -> float:
    """Rough cost (s) of one run of a class: the registry's
    (:meth:`compare.runs.backends.Backend.cost`); what decides how many runs go into one call."""
    backend, trunk = cost_class
    return get_backend(backend).cost({"trunk": trunk} if trunk else {})


def chunks(tasks: list, workers: int) -> list[list]:
    """The ``tasks`` (:class:`.execute.Task`) grouped into worker calls for ``workers``
    processes: runs of one cost class (:func:`_run_cost`) up to :data:`CALL_BUDGET` seconds
    a call, and no fewer than about 8 calls per worker; order kept within a class. The
    calls come longest first (estimated), so the short ones (the analytic reference runs)
    fill the workers' last gaps instead of a long call running alone at the end. Returns
    the calls, each a list of tasks."""
    classes = [_cost_class(t) for t in tasks]
    count = {c: classes.count(c) for c in set(classes)}
    size = {c: max(1, min(int(CALL_BUDGET / _run_cost(c)),
                          n // max(1, 8 * workers))) for c, n in count.items()}
    chunks, open_ = [], {}
    for t, c in zip(tasks, classes):
        group = open_.setdefault(c, [])
        group.append(t)
        if len(group) >= size[c]:
            chunks.append(group)
            open_[c] = []
    chunks += [g for g in open_.values() if g]
    chunks.sort(key=lambda c: -len(c) * _run_cost(_cost_class(c[0])))  # stable
    return chunks
