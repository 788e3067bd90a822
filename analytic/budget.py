"""The work budget of one run, checked before it starts, and the progress of long runs.

A run is refused up front, in one line with its estimate and how to allow it, when its
steps, its memory (the record it keeps) or its estimated wall time exceed the budget:
:data:`MAX_STEPS`, :data:`MAX_BYTES`, :data:`MAX_SECONDS`, each raised deliberately with the
environment variable of its name (``TREEIMPACT_MAX_STEPS`` ...; the command line's
``--max-seconds`` sets ``TREEIMPACT_MAX_SECONDS`` for itself and its workers). The costs per
step are measured per backend (``benchmarks/bench_cost.py`` prints estimate / measured;
figures in docs/budgets.md). An admitted run estimated longer than
:data:`PROGRESS_AFTER_S` reports its progress to the reporter the command line installs
(:func:`set_progress_reporter`); a library caller sees nothing.

The bottom floor of :mod:`treeimpact.analytic` with :mod:`.errors`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass

from treeimpact.analytic.errors import ParameterError

MAX_STEPS = 20_000_000  # the shipped runs take 2e4-6e4 steps, --preset full up to ~1e6
MAX_BYTES = 2_000_000_000  # B: the record of one run (the process's peak: ~0.15 GB more)
MAX_SECONDS = 120.0  # s: estimated wall time of one run (shipped runs: 0.1-10 s)
#: An admitted run estimated longer than this (s) reports its progress.
PROGRESS_AFTER_S = 10.0
#: The environment variable of each budget.
VARIABLES = {"steps": "TREEIMPACT_MAX_STEPS", "bytes": "TREEIMPACT_MAX_BYTES",
             "seconds": "TREEIMPACT_MAX_SECONDS"}


def budget(name: str, default: float) -> float:
    """A work budget from the environment variable ``name`` (a positive number, e.g. 1e8),
    else ``default``; a one-line ParameterError naming the variable when it is not one."""
    text = os.environ.get(name)
    if text is None:
        return float(default)
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(f"{name} = {text!r}: expected a positive number (default "
                             f"{default:.3g}), or unset it")
    return value


@dataclass(frozen=True)
class StepCost:
    """What one step (or sample) of a backend costs: wall seconds and bytes kept, with a
    few words on the model's size (``what``, e.g. "a 66-joint chain")."""

    seconds: float
    bytes: float
    what: str = ""


@dataclass(frozen=True)
class Knob:
    """The input a run's step follows (its step dt grows with it, as a contact's with its
    duration): a refusal names it as typed (``label``, e.g. ``contact.duration`` or
    ``--contact-duration``) with its ``value`` and ``unit`` and the smallest value whose
    run fits the budget, found through ``dt_of`` (value -> dt, s), at most ``high``."""

    label: str
    value: float
    unit: str
    dt_of: Callable[[float], float]
    high: float


def check_work(t_end: float, dt: float, cost: StepCost | float, knob: Knob | None = None
               ) -> int:
    """The steps of a run (t_end / dt), or a one-line ParameterError with the estimate when
    its steps, memory or wall time exceed the budget (module docstring). ``cost``: the
    backend's :class:`StepCost`, or bytes per step alone (no time estimate); ``knob``: the
    input dt follows, named in the refusal with the value that fits."""
    cost = cost if isinstance(cost, StepCost) else StepCost(0.0, float(cost))
    limits = {"steps": budget(VARIABLES["steps"], MAX_STEPS),
              "bytes": budget(VARIABLES["bytes"], MAX_BYTES),
              "seconds": budget(VARIABLES["seconds"], MAX_SECONDS)}
    steps = math.ceil(t_end / dt)
    over = _over(steps, cost, limits)
    if over:
        per = f" of ~{_duration(cost.seconds)}" if cost.seconds else ""
        what = f" ({cost.what})" if cost.what else ""
        text = (f"the run is beyond its budget: {steps:.3g} steps (t_end {t_end:.3g} s / dt "
                f"{dt:.3g} s){per}{what}: {'; '.join(over)}")
        if knob is None:
            raise ParameterError(f"{text}. A shorter --t-end, a coarser trunk or a softer "
                                 "contact; or raise the budget named")
        raise ParameterError(f"{knob.label} = {knob.value:g} {knob.unit}: {text}; "
                             f"{_knob_range(knob, t_end, _fitting_steps(cost, limits))}, "
                             "or a shorter --t-end, or raise the budget named")
    return steps


def _over(steps: int, cost: StepCost, limits: dict) -> list[str]:
    """The budgets (``limits`` by kind) ``steps`` of ``cost`` exceed, one text each."""
    over = [f"{steps:.3g} steps > {limits['steps']:.3g} ({VARIABLES['steps']})"] if (
        steps > limits["steps"]) else []
    if steps * cost.bytes > limits["bytes"]:
        over.append(f"{steps * cost.bytes / 1e9:.3g} GB > {limits['bytes'] / 1e9:.3g} GB "
                    f"({VARIABLES['bytes']})")
    if steps * cost.seconds > limits["seconds"]:
        over.append(f"~{_duration(steps * cost.seconds)} > {limits['seconds']:.3g} s "
                    f"(--max-seconds, {VARIABLES['seconds']})")
    return over


def _fitting_steps(cost: StepCost, limits: dict) -> int:
    """The most steps of ``cost`` within every budget of ``limits``."""
    n = limits["steps"]
    if cost.bytes > 0:
        n = min(n, limits["bytes"] / cost.bytes)
    if cost.seconds > 0:
        n = min(n, limits["seconds"] / cost.seconds)
    return math.floor(n)


def _knob_range(knob: Knob, t_end: float, n_fit: int) -> str:
    """'allowed LABEL >= V UNIT at this t_end': V the smallest value of ``knob`` (3
    digits, rounded up) whose run of ``t_end`` s takes at most ``n_fit`` steps (dt about
    proportional to it: rescaled until it fits), or that none up to ``knob.high`` does."""
    v = knob.value
    for _ in range(50):
        steps = math.ceil(t_end / knob.dt_of(v))
        if steps <= n_fit or v >= knob.high:
            break
        v = min(knob.high, v * steps / max(n_fit, 1) * (1.0 + 1e-9))
    shown = float(f"{v:.3g}")
    if shown < v:  # rounded up: a larger value has a larger step, it fits too
        shown = float(f"{shown + 10.0 ** (math.floor(math.log10(v)) - 2):.3g}")
    if math.ceil(t_end / knob.dt_of(min(shown, knob.high))) > n_fit:
        return f"no {knob.label} up to its largest allowed {knob.high:g} {knob.unit} fits"
    return f"allowed {knob.label} >= {shown:g} {knob.unit} at this t_end"


def _duration(seconds: float) -> str:
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6)):
        if seconds >= scale:
            return f"{seconds / scale:.3g} {unit}"
    return f"{seconds / 1e-9:.3g} ns"


#: The command line's progress reporter: ``reporter(desc, total)`` -> an object with
#: ``update(n)`` and ``close()`` (compare.runs.progress.Progress); None: no progress.
_REPORTER: Callable | None = None


def set_progress_reporter(reporter: Callable | None) -> None:
    """Install (or with None remove) the reporter of long runs' progress."""
    global _REPORTER
    _REPORTER = reporter


@contextmanager
def progress(desc: str, total: int, estimate_s: float):
    """``update(n)`` for a run of ``total`` steps estimated at ``estimate_s`` seconds: the
    reporter's when one is installed and the run is long (:data:`PROGRESS_AFTER_S`), else a
    no-op. ``desc`` names the run on the reporter's line (e.g. the engine)."""
    if _REPORTER is None or not estimate_s >= PROGRESS_AFTER_S:
        yield lambda n: None
        return
    bar = _REPORTER(f"{desc} (estimated {_duration(estimate_s)})", int(total))
    try:
        yield bar.update
    finally:
        bar.close()
