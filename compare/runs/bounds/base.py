"""The per-tree bound records and their registry (the package's docstring says how a
tolerance entry names one)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from treeimpact.analytic.errors import ParameterError

from treeimpact.analytic.results import finite_number

from ..backends import BACKENDS
from ..cache import RunCache


@dataclass(frozen=True)
class Bound:
    """A tolerance for one tree.

    Attributes:
        rel: the relative tolerance on |value - reference| / |reference| (1), finite, >= 0.
        words: how it follows, with this tree's numbers (one clause, no other tree's).
    """

    rel: float
    words: str


@dataclass(frozen=True)
class Pair:
    """What a bound reads: one comparison of the ladder.

    Attributes:
        scenario: the tree's :class:`analytic.Scenario`.
        physics: its :class:`compare.runs.findings.TreePhysics`.
        metric: the metric compared.
        rung: the checked rung's result (``compare.tree.ladder.RungResult``: ``.result`` is its
            SimulationResult, ``.values`` its ladder values).
        reference: the reference rung's result, the same kind of object.
        entry: the tolerance file's entry being evaluated (its ``floor`` and other keys),
            set by :func:`tree_entry`; None outside it.
    """

    scenario: Any
    physics: Any
    metric: str
    rung: Any
    reference: Any
    entry: dict | None = None

    @property
    def value(self) -> float:
        """The checked rung's value of the metric (SI; NaN when missing)."""
        return self.rung.values.get(self.metric, math.nan)

    @property
    def reference_value(self) -> float:
        """The reference rung's value of the metric (SI; NaN when missing)."""
        return self.reference.values.get(self.metric, math.nan)


def relative_step(value, reference) -> float:
    """(value - reference) / |reference| (1), what every tolerance is a bound on; NaN when
    either is not a finite number or the reference is 0."""
    if not (finite_number(value) and finite_number(reference)) or reference == 0:
        return math.nan
    return (value - reference) / abs(reference)


#: The engines' runs at half their step, one per (tree, backend, options) and process.
_HALF_STEP = RunCache()


def half_step_run(scenario, rung_result):
    """The :class:`compare.runs.cache.Run` of ``rung_result``'s rung (a
    ``compare.tree.ladder.RungResult`` of ``scenario``) again at half the step its run took
    (``dt`` given: a fixed step), made once a process (the bounds that read a first-order
    step error share it)."""
    dt = float(rung_result.result.model["dt"])
    return _HALF_STEP.run(scenario, rung_result.rung.backend, **dict(rung_result.rung.options),
                          dt=0.5 * dt)


BoundFunction = Callable[[Pair], Bound]
#: name -> the function that evaluates the bound on a :class:`Pair`.
BOUNDS: dict[str, BoundFunction] = {}


#: The bounds that read an engine run's time step (``model["dt"]``) from both runs.
NEEDS_STEP: set[str] = set()
#: The bounds that read their entry's ``floor`` (a relative error that stays at any step).
READS_FLOOR: set[str] = set()


def register(name: str, *, step: bool = False,
             floor: bool = False) -> Callable[[BoundFunction], BoundFunction]:
    """Decorator: register the bound ``name`` (the tolerance file's ``bound = "name"``);
    ``step``: it reads the runs' time step (a run that records none is held to no step
    error, :func:`tree_entry`); ``floor``: it reads its entry's ``floor`` (checked by
    :func:`validate_bound`)."""
    def deco(fn: BoundFunction) -> BoundFunction:
        if name in BOUNDS:
            raise ValueError(f"bound {name!r} registered twice")
        BOUNDS[name] = fn
        if step:
            NEEDS_STEP.add(name)
        if floor:
            READS_FLOOR.add(name)
        return fn
    return deco


def _records_step(pair: Pair) -> bool:
    """Whether every engine run of ``pair`` records its time step (``model["dt"]``); the
    exact references (no engine, no step) need none."""
    runs = [r.result for r in (pair.rung, pair.reference) if r.result is not None]
    return all("dt" in r.model for r in runs
               if getattr(BACKENDS.get(r.backend), "engine", False))


def validate_bound(where: str, entry: dict) -> None:
    """Refuse (ParameterError) a tolerance entry whose ``bound`` is not a registered one,
    that gives both a bound and a fixed ``rel``, or whose ``floor`` is not a relative error
    in [0, 1) read by its bound (a floor no bound reads would be silently ignored);
    ``where`` names the entry in the error."""
    name = entry.get("bound")
    if "floor" in entry and name not in READS_FLOOR:
        raise ParameterError(f"{where}.floor: read only with bound = "
                             f"{' or '.join(repr(b) for b in sorted(READS_FLOOR))}")
    if name is None:
        return
    floor = entry.get("floor", 0.0)
    if isinstance(floor, bool) or not isinstance(floor, (int, float)) or not 0 <= floor < 1:
        raise ParameterError(f"{where}.floor = {floor!r}: allowed a relative error in [0, 1)")
    if name not in BOUNDS:
        raise ParameterError(f"{where}.bound = {name!r}: allowed {', '.join(sorted(BOUNDS))}")
    if "rel" in entry or entry.get("report_only"):
        raise ParameterError(f"{where}: give bound or rel (or report_only), not both")


def tree_entry(entry: dict | None, pair: Pair) -> dict | None:
    """``entry`` as it applies to ``pair``'s tree: a ``bound`` evaluated into ``rel``, its
    words appended to the reason; an entry without a bound (or None) unchanged."""
    if entry is None or "bound" not in entry:
        return entry
    if entry["bound"] in NEEDS_STEP and not _records_step(pair):
        return {**entry, "rel": 0.0, "reason": f"{entry['reason']}: the run records no time "
                "step (dt), so no step error is allowed"}
    b = BOUNDS[entry["bound"]](dataclasses.replace(pair, entry=entry))
    if not (math.isfinite(b.rel) and b.rel >= 0):
        raise ValueError(f"bound {entry['bound']!r} gave rel = {b.rel!r} on {pair.metric}")
    return {**entry, "rel": float(b.rel), "reason": f"{entry['reason']}: {b.words}"}
