"""A sweep planned before anything runs: its targets (backends with fixed options, each
compared with the one below it), every grid point applied to the scenario, what no point
could run refused, and the rows grouped into tasks (one backend call per distinct inputs).

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

import json
from collections import OrderedDict
from dataclasses import dataclass

from treeimpact.analytic.errors import ParameterError, one_line
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.compare.runs.backends import BACKENDS, ENGINES, get_backend
from treeimpact.compare.runs.cache import INVALID, options_key, scenario_key
from treeimpact.compare.runs.rungs import RungKind, analytic_samples, rung_table

from .apply import apply_point
from .cost import ANALYSIS_COST
from .execute import Task
from .grid import INPUT, OPTION, RECORD, Grid, point_key

REFERENCE_BACKENDS = ("analytic", "soft", "beam")


@dataclass(frozen=True)
class Target:
    """What one row runs: ``backend`` with fixed ``options``, compared with ``previous``."""

    id: str
    backend: str
    options: tuple = ()  # sorted (name, value) pairs
    previous: str | None = None
    kind: RungKind = RungKind.MODEL  # the ladder's kind; MODEL for an engine run as
    # configured, compared with soft (numerics and trunk/pendulum together)
    drop: tuple = ()  # swept options this target ignores (segments for an SDOF trunk)

    @property
    def reference(self) -> bool:
        """Whether the target runs a reference rung (:data:`REFERENCE_BACKENDS`): a swept
        option reaches it only where its simulate() takes it, and its trunk options are
        not read as an engine's."""
        return self.backend in REFERENCE_BACKENDS


def check_backends(backends, flag: str = "--backend") -> list[str]:
    """The backend names of ``--backend``, ``backends`` (a list or a comma-separated
    string), each once, in order; a one-line ParameterError naming ``flag`` (the public
    API's: ``backends`` in Python) and the allowed ones for an unknown name."""
    if isinstance(backends, str):
        backends = [b.strip() for b in backends.split(",") if b.strip()]
    out = []
    for b in backends:
        try:
            get_backend(b)
        except ParameterError:
            raise ParameterError(f"{flag} {b!r}: allowed {', '.join(BACKENDS)} "
                                 f"(comma-separated)") from None
        if b not in out:
            out.append(b)
    return out


#: The form of one fixed option: ``--option``'s, and the API's ``options`` given as specs.
OPTION_FORM = "[BACKEND.]NAME=VALUE, e.g. trunk=sdof or mujoco.integrator=RK4"


def check_options(options, backends, *, label: str = "--option",
                  backends_label: str = "--backend") -> dict:
    """``{backend: {name: value}}`` of the fixed ``options``: that dict, or specs
    :data:`OPTION_FORM` (``--option``'s; no BACKEND: every engine among ``backends``, the
    sweep's), each name and value checked against its backend's OPTIONS. A one-line
    ParameterError names ``label`` (the API's ``options`` in Python) and the entry as a
    spec, ``backends_label`` where the spec names no engine of the sweep."""
    if isinstance(options, dict):
        specs = [(f"{b}.{name}={value}", b, name, value)
                 for b, table in options.items() for name, value in table.items()]
    else:
        specs = [_split_spec(spec, label) for spec in options or ()]
    out: dict = {}
    for spec, backend, name, value in specs:
        targets = [backend] if backend else [b for b in backends if b in ENGINES]
        if not targets:
            raise ParameterError(f"{label} {spec!r}: no engine among {backends_label} "
                                 f"{','.join(backends)}; write BACKEND.NAME=VALUE")
        if backend:  # the sweep's own backends are checked already
            check_backends([backend], flag=f"{label} {spec!r}: backend")
        for b in targets:
            table = get_backend(b).options()
            option = table.get(name)
            if option is None:
                raise ParameterError(
                    f"{label} {spec!r}: backend {b!r} has no option {name!r}; allowed: "
                    f"{', '.join(sorted(k for k, o in table.items() if o.cli))}")
            if isinstance(value, str) and not option.choices:
                value = _number(value)
            out.setdefault(b, {})[name] = option.check(name, value,
                                                       label=f"{label} {spec!r}: {name}")
    return out


def _split_spec(spec, label: str) -> tuple:
    """(spec, backend or None, name, value text) of one :data:`OPTION_FORM` spec."""
    if not isinstance(spec, str) or spec.count("=") != 1 or not spec.split("=")[0].strip() \
            or not spec.split("=")[1]:
        raise ParameterError(f"{label} {spec!r}: expected {OPTION_FORM}")
    name, text = (s.strip() for s in spec.split("="))
    backend = None
    if "." in name:
        backend, name = name.split(".", 1)
        if not name:
            raise ParameterError(f"{label} {spec!r}: expected {OPTION_FORM}")
    return spec, backend, name, text


def _number(text: str):
    """The number an option's value spells, or the text (the option's check names it)."""
    try:
        return float(text)
    except ValueError:
        return text


def make_targets(backends=("analytic",), *, ladder: bool = False,
                 options: dict | None = None) -> list[Target]:
    """The targets of a sweep (see the module docstring) on ``backends`` (as
    :func:`check_backends` takes them). ``ladder``: the ladder's own rung table
    (compare.runs.rungs.rung_table) for the engines asked for, chain segments left to the grid;
    else the reference rungs asked for (analytic always), each compared with the one below,
    and each engine as configured compared with the top one. ``options`` maps a backend name
    to fixed options for it (``{"mujoco": {"trunk": "sdof"}}``)."""
    names = check_backends(backends)
    options = options or {}
    for b in options:
        check_backends([b])

    def opts(backend, extra=()):
        return tuple(sorted({**dict(extra), **options.get(backend, {})}.items()))


    if ladder:  # the ladder's own rung table, chain segments left to the grid
        engines = [b for b in names if b not in REFERENCE_BACKENDS]
        return [Target(r.id, r.backend, opts(r.backend, r.options), r.previous, r.kind, r.drop)
                for r in rung_table(engines)]
    # the reference rungs of the same table that were asked for, each compared with the one
    # below it; the engines' default trunk is the hinged chain: the beam is its reference
    table = {r.id: r for r in rung_table(())}
    targets, below = [], None
    for rid in ("analytic", "soft", "beam"):
        if rid == "analytic" or rid in names:
            r = table[rid]
            targets.append(Target(r.id, r.backend, opts(r.backend, r.options), below, r.kind))
            below = rid
    for eng in (b for b in names if b not in REFERENCE_BACKENDS):  # engines (or any other)
        targets.append(Target(eng, eng, opts(eng), below, RungKind.MODEL))
    return targets


def apply_points(scenario: Scenario, grid: Grid) -> list[tuple]:
    """Every grid point with what :func:`~compare.studies.sweep.apply.apply_point` makes of it:
    ``(point, (scenario, options))``, or ``(point, ParameterError)`` for an invalid point.
    Computed once per sweep (:func:`check_grid` and :func:`plan` both read it)."""
    out = []
    for point in grid.points():
        try:
            out.append((point, apply_point(scenario, point)))
        except ParameterError as exc:
            out.append((point, exc))
    return out


def plan(scenario: Scenario, grid: Grid, targets: list[Target], *, identify: bool = True,
         done: set | None = None, applied: list | None = None, analysis: str | None = None,
         part: int = 0):
    """(tasks to run, rows already decided without running: invalid points) of the
    ``scenario`` over ``grid`` on ``targets``: one :class:`Task` per distinct backend call,
    holding its rows. ``identify``: the paper's identification on each run's record (an
    analytic run sampled for it); ``done``: the (point key, target id) pairs an earlier run
    finished, skipped; ``applied``: :func:`apply_points` of this scenario and grid, when
    already computed; ``analysis``: ``module:function`` run on each result instead of the
    standard columns (a run cheaper than :data:`ANALYSIS_COST` is repeated per record);
    ``part``: the index of this sweep among :func:`.run.run_sweeps`' specs."""
    done = done or set()
    tasks: OrderedDict[str, Task] = OrderedDict()
    immediate = []
    accepted = {t.id: _accepted(t.backend) for t in targets}
    for point, outcome in (applied if applied is not None else apply_points(scenario, grid)):
        pk = point_key(point)
        record = {a.parameter.target: point[a.name] for a in grid.axes
                  if a.parameter.kind in (RECORD, INPUT)}  # the analysis's, not the run's
        todo = [t for t in targets if (pk, t.id) not in done]
        if not todo:
            continue
        if isinstance(outcome, ParameterError):
            for t in todo:
                immediate.append(row_base(scenario, point, pk, t) | {
                    "status": INVALID, "error": one_line(outcome), "t_end": scenario.t_end})
            continue
        scen, popts = outcome
        for t in todo:
            opts = dict(t.options)
            for name, value in popts.items():
                if name in t.drop or (t.reference and name not in accepted[t.id]):
                    continue  # the option does not change this target's model
                opts[name] = value
            if not t.reference:
                opts = _trunk_options(opts, accepted[t.id])
            if t.backend == "analytic" and identify and "samples" in accepted[t.id] \
                    and "samples" not in opts:
                opts["samples"] = analytic_samples(scen.t_end)
            key = [scenario_key(scen), t.backend, options_key(opts)]
            run = json.dumps(key, default=str, sort_keys=True)
            if analysis is not None and record and \
                    get_backend(t.backend).cost(opts) < ANALYSIS_COST:
                # a run cheaper than its analysis is repeated per record: the records'
                # analyses spread over the workers instead of queueing on one (a worker
                # makes the run once for its consecutive tasks of one run: Task.run)
                key.append(record)
            key = json.dumps(key, default=str, sort_keys=True)
            task = tasks.get(key)
            if task is None:
                task = tasks[key] = Task(key, scen, get_backend(t.backend), opts, identify,
                                         analysis, part, run=run)
            task.rows.append((point, pk, t, record))
    return list(tasks.values()), immediate


def _accepted(backend: str) -> set:
    """The options ``backend``'s simulate() takes (empty when it is not installed: its rows
    are then skipped with the backend's own reason)."""

    try:
        return set(get_backend(backend).options())
    except ParameterError:
        return set()


def _trunk_options(opts: dict, accepted: set) -> dict:
    """An engine's options with ``segments`` read against its trunk: ``segments = 1`` is the
    one-degree-of-freedom trunk (``trunk = sdof``, eq 7; a hinged chain needs 2 or more), and
    an SDOF trunk has no segments (dropped: they do not change its model)."""
    if "trunk" not in accepted or "segments" not in opts:
        return opts
    if opts["segments"] == 1:
        return {k: v for k, v in opts.items() if k != "segments"} | {"trunk": "sdof"}
    if opts.get("trunk") == "sdof":
        return {k: v for k, v in opts.items() if k != "segments"}
    return opts


def check_grid(scenario: Scenario, grid: Grid, targets: list[Target],
               label: str | None = None) -> list[tuple]:
    """Refuse, before anything runs, what no point of ``grid`` applied to ``scenario`` could
    run on the ``targets`` (one-line ParameterError naming the ``--grid`` spec): an engine
    option that no backend of the sweep takes, and an axis value outside its parameter's
    range at every point (``restitution=2``). A point that is invalid only in combination
    with other axes (a clamp height above one of the swept lengths) is kept: it becomes an
    ``invalid`` row and the sweep goes on; ``label``: what the message names instead of the
    spec (a grid a study made, not one typed). Returns :func:`apply_points` of the grid, for
    :func:`plan`."""
    accepted = set().union(*(_accepted(t.backend) for t in targets))
    for ax in grid.axes:
        p = ax.parameter
        if p.kind == OPTION and p.target not in accepted:
            raise ParameterError(
                f"--grid {ax.spec()!r}: no backend of this sweep "
                f"({', '.join(dict.fromkeys(t.backend for t in targets))}) takes the option "
                f"{p.target!r}; allowed: {', '.join(sorted(accepted))}")
    applied = apply_points(scenario, grid)
    errors = [one_line(o) if isinstance(o, ParameterError) else None for _, o in applied]
    if not any(errors):
        return applied
    for ax in grid.axes:
        for v in ax.values:
            errs = [e for (point, _), e in zip(applied, errors) if point[ax.name] == v]
            if all(errs):
                where = label or f"--grid {ax.spec()!r}"
                raise ParameterError(f"{where}: {errs[0]} (at every point of the grid)")
    return applied


def row_base(scenario, point, pk, target: Target) -> dict:
    """The columns of a row that say what it is: scenario, point (and its key ``pk``),
    target, backend, kind and the rung it is compared with, and the point's axis values."""
    return {"scenario": scenario.name, "point": pk, "target": target.id,
            "backend": target.backend, "kind": target.kind, "previous": target.previous,
            **point}
