"""The registry of simulation backends and engines.

An engine is one folder (its package), which declares itself beside its definition (its
``DECLARATION``: analytic.engine.declaration.EngineDeclaration: name, label, costs,
variants, colours, distributions), and its name in :data:`ENGINE_FOLDERS`; the registry
makes its :class:`Engine` from that declaration, and the ladder, the pool, the report,
``treeimpact contact``, the provenance and the layer test read it (docs/engines.md,
"Adding an engine"); the analytic references are declared beside their definitions too
(analytic.references). Each backend's ``simulate(scenario, **options)`` returns
:class:`analytic.results.SimulationResult` and its ``modes(scenario, **options)`` the modes
dict. Options a backend does not take are refused with a
one-line error instead of being ignored.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import os
import sys
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.references import REFERENCES
from treeimpact.analytic.model.options import (
    OVERRIDES,
    as_typed,
    numerical_options,
    scenario_as_run,
)

from .names import did_you_mean


@contextmanager
def quiet_stdout():
    """Send what C extensions print on file descriptor 1 to stderr for the duration."""
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError):  # no real stdout (e.g. captured): nothing to protect
        yield
        return
    try:
        os.dup2(2, 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


@contextmanager
def worded_c_output(source: str, why: str = ""):
    """Run the block with file descriptors 1 and 2 sent to a temporary file, so that what a
    C library writes there (LAPACK's argument errors, an engine's notes) never reaches the
    terminal as it is; afterwards each distinct line is told on stderr as treeimpact's own
    warning, ``treeimpact: warning: SOURCE: line (WHY)`` (``source``: the library's name;
    ``why``: why its lines do not matter, or ""), with its count when repeated (a line
    already starting with ``treeimpact:`` passes as it is)."""
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = os.dup(1), os.dup(2)
    except (OSError, ValueError):  # no real file descriptors (captured): nothing to word
        yield
        return
    with tempfile.TemporaryFile() as tmp:
        try:
            os.dup2(tmp.fileno(), 1)
            os.dup2(tmp.fileno(), 2)
            yield
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            tmp.seek(0)
            _tell(tmp.read().decode("utf-8", errors="replace"), source, why)


def _tell(text: str, source: str, why: str) -> None:
    counts: dict = {}
    for line in text.splitlines():
        line = " ".join(line.replace("**", " ").split())
        if line:
            counts[line] = counts.get(line, 0) + 1
    for line, n in counts.items():
        if line.startswith("treeimpact:"):
            print(line, file=sys.stderr)
            continue
        times = f", {n} times" if n > 1 else ""
        because = f" ({why}{times})" if why else f" ({n} times)" if n > 1 else ""
        print(f"treeimpact: warning: {source}: {line}{because}", file=sys.stderr)


#: ``module:NAME`` -> what it names, once loaded (a run's two look-ups cost a
#: redirection of stdout each otherwise: the exact model's runs are 0.2 ms).
_LOADED: dict = {}


@dataclass(frozen=True)
class Backend:
    """A registered backend: its name, where its ``simulate`` (and ``modes``) live, its
    options table and what the ladder, the pool and the report read about it."""

    name: str
    simulate_ref: str
    modes_ref: str | None
    description: str
    #: a physics engine with its own trunk models (the ladder's engine rungs), not an
    #: analytic reference
    engine: bool = False
    #: rough wall time (s) of one run of a shipped scenario on a 2-core VM, by trunk model
    #: (None: the backend's only or default model): what orders and groups parallel runs
    run_cost: tuple = ()
    #: (option, values) whose values make separate speed-accuracy curves of an engine
    #: (compare.studies.speed), or None
    variants: tuple | None = None
    #: the report's line colours of an engine's rungs (SDOF, chain, chain + full pendulum,
    #: its own elastic rod where it has one)
    shades: tuple = ()
    #: ``module:NAME`` of the backend's options table; None: the ``OPTIONS`` of the module
    #: its ``simulate`` lives in
    options_ref: str | None = None

    def cost(self, options: dict) -> float:
        """Rough wall time (s) of one run with ``options`` (:attr:`run_cost`; 1 s unknown)."""
        costs = dict(self.run_cost)
        return costs.get(options.get("trunk"), costs.get(None, 1.0))

    def _load(self, ref: str):
        loaded = _LOADED.get(ref)
        if loaded is not None:
            return loaded
        module, func = ref.split(":")
        try:
            with quiet_stdout():  # pybullet prints its build time on import: keep JSON clean
                loaded = getattr(importlib.import_module(module), func)
        except (ImportError, AttributeError) as exc:
            raise ParameterError(f"backend {self.name!r} is not available here: {exc}") from None
        _LOADED[ref] = loaded
        return loaded

    def options(self) -> dict:
        """The backend's options, name -> :class:`treeimpact.analytic.model.options.Option`:
        the ``OPTIONS`` of the module its ``simulate`` lives in (read without running it)."""
        return self._load(self.options_ref or self.simulate_ref.split(":")[0] + ":OPTIONS")

    def offers(self, option: str, value) -> bool:
        """Whether the backend's ``option`` takes the word ``value`` (its Option's choices);
        False where the option table cannot be read here (the package is missing)."""
        try:
            choices = getattr(self.options().get(option), "choices", None)
        except ParameterError:
            return False
        return bool(choices) and value in choices

    def simulate(self, scenario, **options):
        """The backend's result for ``scenario`` with ``options``: :meth:`run`'s result."""
        return self.run(scenario, **options)[1]

    def run(self, scenario, **options) -> tuple:
        """``(scenario as run, result)`` of ``scenario`` with ``options``, each checked by
        its Option (one the backend does not take is refused). The one way a physical input
        reaches a backend: the options that override a scenario field
        (analytic.model.options.OVERRIDES) are applied to the scenario here, once
        (:func:`scenario_as_run`), and the backend receives that scenario and its numerical
        options only. The result is checked before anyone reports it (a diverged run raises
        :class:`analytic.errors.SimulationDiverged`: never numbers)."""
        # lazy: +95 ms at import otherwise (numpy), which this module's other callers do not need
        from treeimpact.analytic.results import check_plausible

        func = self._load(self.simulate_ref)
        table = self.options()
        options = self._checked(options, table, set(table))
        try:  # a refusal names a field as the user typed it: by its flag
            as_run = scenario_as_run(scenario, options)
            result = func(as_run, **numerical_options(options))
        except ParameterError as exc:
            exc.args = (as_typed(str(exc), options), *exc.args[1:])
            raise
        shown = as_run.to_dict()
        shown["t_end"] = result.scenario.get("t_end", shown["t_end"])  # an engine's own
        return as_run, check_plausible(dataclasses.replace(result, scenario=shown))

    def modes(self, scenario, **options):
        """The backend's modes dict for ``scenario`` (static stiffness at a, N/m; omegas,
        rad/s) beside the beam's; its ``options`` checked as :meth:`simulate`'s."""
        if self.modes_ref is None:
            raise ParameterError(f"backend {self.name!r} has no modes")
        func = self._load(self.modes_ref)
        accepted = {p.name for p in inspect.signature(func).parameters.values()
                    if p.kind == p.KEYWORD_ONLY}
        return func(scenario, **self._checked(options, self.options(), accepted))

    def _checked(self, options: dict, table: dict, accepted: set) -> dict:
        """``options`` with each value checked by its Option; an option ``accepted`` does
        not hold is refused, naming what the backend takes. Every refused option is named
        in the one line (``; ``-joined), each with its allowed values or range."""
        out, refused = {}, []
        for key, value in options.items():
            if key not in accepted:
                known = [k for k in sorted(accepted) if k not in table or table[k].cli]
                shown = ", ".join("--" + k.replace("_", "-") for k in known)
                refused.append(f"--{key.replace('_', '-')}: not an option of backend "
                               f"{self.name!r} (its options: {shown or 'none'})"
                               f"{did_you_mean(key, known)}")
                continue
            try:
                # a scenario field's override is checked once, where it enters the
                # scenario (scenario_as_run: the field's own range, named by its flag)
                out[key] = table[key].check(key, value) if key in table and value is not None \
                    and key not in OVERRIDES else value
            except ParameterError as exc:
                refused.append(str(exc))
        if refused:
            raise ParameterError("; ".join(refused))
        return out


#: The registered backends, name -> :class:`Backend`: the analytic references as analytic
#: declares them (analytic.references.REFERENCES), then each engine registered below.
BACKENDS = {d.name: Backend(d.name, d.simulate, d.modes, d.description, run_cost=d.run_cost)
            for d in REFERENCES}


@dataclass(frozen=True)
class Engine:
    """A physics engine's one registration: everything the rest of compare knows about it.

    ``backend``: its :class:`Backend` (simulate/modes refs, run_cost, variants, shades;
    registered with ``engine=True``); ``label``: its name as printed ("MuJoCo");
    ``folder``: its source folder, installed as ``treeimpact.<folder>`` (pyproject.toml's
    package list must name it: tests/test_layers.py fails otherwise); ``package``: the
    distribution name the provenance reports its version under, read from the first
    installed of ``distributions``; ``contact``: ``module:NAME`` of its
    :class:`compare.runs.contact_engines.ContactSide` (``treeimpact contact``), or None: the
    engine gives no contact settings. docs/engines.md, "Adding an engine"."""

    backend: Backend
    label: str
    folder: str
    package: str
    distributions: tuple = ()
    contact: str | None = None

    @property
    def name(self) -> str:
        """The engine's backend name (``--backend``, the rung ids)."""
        return self.backend.name

    def contact_side(self):
        """The engine's ContactSide (loaded from :attr:`contact`), or None."""
        return None if self.contact is None else self.backend._load(self.contact)


#: The registered engines, name -> :class:`Engine`, in the order the ladder shows them.
ENGINE_REGISTRY: dict = {}


def register_engine(engine: Engine) -> Engine:
    """Register ``engine`` (its backend joins :data:`BACKENDS` as an engine); a name already
    taken is refused (ParameterError). Returns ``engine``."""
    if engine.name in BACKENDS:
        raise ParameterError(f"backend {engine.name!r} is already registered")
    BACKENDS[engine.name] = dataclasses.replace(engine.backend, engine=True)
    ENGINE_REGISTRY[engine.name] = engine
    return engine


def unregister_engine(name: str) -> None:
    """Undo :func:`register_engine` for the engine called ``name``."""
    engine = ENGINE_REGISTRY.pop(name)
    del BACKENDS[name]
    b = engine.backend
    for ref in (b.simulate_ref, b.modes_ref, engine.contact,
                b.options_ref or b.simulate_ref.split(":")[0] + ":OPTIONS"):
        _LOADED.pop(ref, None)  # what it loaded goes with it


@contextmanager
def engine_registered(engine: Engine):
    """``engine`` registered for the duration of the block, then unregistered."""
    register_engine(engine)
    try:
        yield engine
    finally:
        unregister_engine(engine.name)


def engines(*, contact: bool = False) -> tuple:
    """The names of the engines registered now, in registration order (``contact``: only
    those that give contact settings, ``treeimpact contact``'s)."""
    return tuple(name for name, e in ENGINE_REGISTRY.items()
                 if not contact or e.contact is not None)


#: The engine packages (folders), in the order the ladder and the studies show them: each
#: declares itself beside its definition (its ``DECLARATION``,
#: analytic.engine.declaration), which the registry reads without importing the engine.
ENGINE_FOLDERS = ("mujoco_models", "bullet_models")
#: compare's check of an engine's contact settings (``treeimpact contact``), by engine:
#: compare's own code about that engine (compare.runs.contact_engines).
CONTACT_SIDES = {"mujoco": "treeimpact.compare.runs.contact_engines:MUJOCO",
                 "bullet": "treeimpact.compare.runs.contact_engines:BULLET"}


def declared_engine(folder: str) -> Engine:
    """The :class:`Engine` the package ``treeimpact.<folder>`` declares (its DECLARATION:
    its simulate and modes are the package's own, its options the package's OPTIONS)."""
    package = f"treeimpact.{folder}"
    d = importlib.import_module(package).DECLARATION
    return Engine(Backend(d.name, f"{package}:simulate", f"{package}:modes", d.description,
                          run_cost=d.run_cost, variants=d.variants, shades=d.shades),
                  label=d.label, folder=folder, package=d.package,
                  distributions=d.distributions, contact=CONTACT_SIDES.get(d.name))


for _folder in ENGINE_FOLDERS:
    register_engine(declared_engine(_folder))

#: The shipped engines, in the order the ladder and the studies show them (an engine
#: registered later, e.g. by a test, is in :func:`engines` and :data:`ENGINE_REGISTRY`).
ENGINES = engines()


def get_backend(name: str) -> Backend:
    """The backend called ``name``, or a one-line ParameterError naming --backend."""
    try:
        return BACKENDS[name]
    except KeyError:
        raise ParameterError(
            f"--backend = {name!r}: allowed {', '.join(BACKENDS)}") from None
