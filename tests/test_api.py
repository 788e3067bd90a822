"""The public API (issue 34 item 4): in Python's words, one unit convention (SI, angles in
degrees named ``_deg``), typed frozen results, errors that name keyword arguments, the
command line's defaults, and a documented name for everything it exports or returns."""

from __future__ import annotations

import dataclasses
import inspect
import math
import re
import typing

import pytest

import treeimpact as ti
from treeimpact.compare.interface.api_studies import REPORT_DIR, SWEEP_BACKENDS, SWEEP_SCENARIO
from treeimpact.compare.studies.sweep.run import SweepResult
from treeimpact.compare.tree.ladder import Ladder

#: What the API returns without exporting it (ladder(), sweep()).
RETURNED = (Ladder, SweepResult)
PUBLIC = [getattr(ti, name) for name in ti.__all__]
FUNCTIONS = [o for o in PUBLIC if inspect.isfunction(o)]
CLASSES = [o for o in PUBLIC if inspect.isclass(o)] + list(RETURNED)


def _section(doc: str, name: str) -> str:
    """The text of a Google-style section (``Args:``) up to the next one."""
    m = re.search(rf"^\s*{name}:\s*$(.*?)(?=^\s*[A-Z][a-z]+:\s*$|\Z)", doc, flags=re.M | re.S)
    return m.group(1) if m else ""


@pytest.mark.parametrize("func", FUNCTIONS, ids=[f.__name__ for f in FUNCTIONS])
def test_every_public_function_documents_its_arguments_returns_and_raises(func):
    doc = inspect.getdoc(func) or ""
    params = [p for p in inspect.signature(func).parameters.values()
              if p.kind is not p.VAR_KEYWORD or p.name == "options"]
    args = _section(doc, "Args")
    for p in params:
        shown = f"**{p.name}" if p.kind is p.VAR_KEYWORD else p.name
        assert re.search(rf"^\s*{re.escape(shown)}:", args, flags=re.M), (func.__name__, p.name)
    assert _section(doc, "Returns").strip(), func.__name__
    assert _section(doc, "Raises").strip(), func.__name__


#: The units a float field's description may name (SI and its derived units; 1: none; the
#: ``unit`` field of a result that carries its own).
UNIT = re.compile(r"(?<![\w/])(kg|m|s|N|J|Pa|rad|Hz|deg|1|m/s|N/m|N s/m|N s/m\^2|kg/m\^3|"
                  r"N m/rad|rad/s|m/s\^2|1/s|m s|N s|``unit``)(?![\w^])")


def _fields(cls):
    if dataclasses.is_dataclass(cls):
        return [(f.name, f.type) for f in dataclasses.fields(cls)]
    return []


@pytest.mark.parametrize("cls", CLASSES, ids=[c.__name__ for c in CLASSES])
def test_every_public_class_documents_each_field_with_its_unit(cls):
    doc = inspect.getdoc(cls) or ""
    assert doc.strip(), cls.__name__
    if issubclass(cls, Exception):
        return
    attrs = _section(doc, "Attributes")
    hints = typing.get_type_hints(cls) if dataclasses.is_dataclass(cls) else {}
    for name, _ in _fields(cls):
        m = re.search(rf"^\s*{name}:(.*?)(?=^\s*\w+:|\Z)", attrs, flags=re.M | re.S)
        assert m, (cls.__name__, name)
        if hints.get(name) in (float, float | None):  # a number: its unit named
            assert UNIT.search(m.group(1)), (cls.__name__, name, m.group(1))


@pytest.mark.parametrize("func", FUNCTIONS, ids=[f.__name__ for f in FUNCTIONS])
def test_what_a_function_returns_is_a_documented_public_type(func):
    ret = typing.get_type_hints(func).get("return")
    if inspect.isclass(ret) and ret.__module__.startswith("treeimpact"):
        assert ret in CLASSES, (func.__name__, ret)


def test_results_are_typed_and_frozen():
    tree = ti.load_scenario("central-leader")
    run = ti.simulate(tree)
    assert isinstance(run, ti.Simulation) and isinstance(run.metrics, ti.Metrics)
    assert isinstance(run.model, ti.Model) and isinstance(run.scenario, ti.Scenario)
    assert run.metrics.x_max == run.result.metrics["x_max"]  # the backend's own number
    assert run.model.M_T == pytest.approx(110.0, rel=1e-9)  # Table 1 (the scenario's M_T)
    modes = ti.modes(tree, backend="beam")
    assert isinstance(modes, ti.Modes) and isinstance(modes.model, ti.TrunkModes)
    for obj in (run, run.metrics, run.model, modes, modes.model):
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(obj, _fields(type(obj))[0][0], None)
    assert tuple(f.name for f in dataclasses.fields(ti.Metrics)) == tuple(ti.METRIC_UNITS)


def test_the_scenario_of_a_run_is_the_scenario_as_run():
    """docs/cli.md said scenario.* is "as run" while it kept 0.0005 after
    --contact-duration 0.002."""
    run = ti.simulate("open-center", backend="soft", contact_duration=0.002, restitution=0.3)
    assert run.scenario.contact == ti.Contact(restitution=0.3, duration=0.002)
    assert run.result.scenario["contact"] == {"restitution": 0.3, "stiffness": None,
                                              "duration": 0.002}


@pytest.mark.parametrize("backend", ["analytic", "soft", "beam", "mujoco", "bullet"])
def test_a_physical_input_reaches_a_backend_one_way_only(monkeypatch, backend):
    """A run option that overrides a scenario field (analytic.model.options.OVERRIDES) is
    applied to the scenario once, at the backends' door, and the backend receives that
    scenario and its numerical options only (issue 51 item 2): here each backend's simulate
    is replaced by a spy that records what it is given."""
    from treeimpact.analytic.model.options import OVERRIDES
    from treeimpact.compare.runs import backends as B

    seen = {}

    def spy(scenario, **options):
        seen.update(scenario=scenario, options=options)
        raise RuntimeError("spy")

    b = B.get_backend(backend)
    monkeypatch.setitem(B._LOADED, b.simulate_ref, spy)  # the loaded function, replaced
    numerical = {"elements": 4} if backend == "beam" else {}
    offered = set(b.options())
    pad = next((p for p in ("contact_duration", "contact_stiffness") if p in offered), None)
    physical = {"restitution": 0.3, "t_end": 0.05}
    if pad is not None:  # the Newton model has no pad
        physical[pad] = 0.002 if pad == "contact_duration" else 3e6
    assert set(physical) <= set(OVERRIDES) and set(physical) <= offered
    with pytest.raises(RuntimeError, match="spy"):
        b.simulate(ti.load_scenario("open-center"), **physical, **numerical)
    assert seen["options"] == numerical  # nothing physical besides the scenario
    contact = seen["scenario"].contact
    assert contact.restitution == 0.3 and seen["scenario"].t_end == 0.05
    want = {None: (5e-4, None), "contact_duration": (0.002, None),
            "contact_stiffness": (None, 3e6)}[pad]  # open-center's own pad where none given
    assert (contact.duration, contact.stiffness) == want


@pytest.mark.parametrize("backend", ["analytic", "soft", "beam", "mujoco", "bullet"])
def test_no_backend_function_takes_a_physical_input_beside_the_scenario(backend):
    """The backends' own functions take (scenario, numerical options): none has a keyword of
    analytic.model.options.OVERRIDES (e, the pad, t_end), which only the scenario carries
    (issue 51 item 2); the engines' setup and batch functions neither."""
    import importlib
    import inspect

    from treeimpact.analytic.model.options import OVERRIDES
    from treeimpact.compare.runs import backends as B

    b = B.get_backend(backend)
    module = importlib.import_module(b.simulate_ref.split(":")[0])
    funcs = [b._load(b.simulate_ref)] + [getattr(module, n) for n in ("make_setup",
                                                                       "simulate_batch")
                                         if hasattr(module, n)]
    for func in funcs:
        taken = set(inspect.signature(func).parameters) & set(OVERRIDES)
        assert not taken, (func.__qualname__, taken)


def test_a_run_option_is_checked_once_where_it_enters_the_scenario():
    """An override out of range is refused by the scenario's own field check (the registry's
    range) and named by its flag as typed, on a backend that takes it: the same line the
    field gives, the field's name replaced."""
    from treeimpact.analytic.errors import ParameterError
    from treeimpact.analytic.model.parameters import Contact
    from treeimpact.compare.runs.backends import get_backend

    with pytest.raises(ParameterError) as field:
        Contact(restitution=1.5)
    with pytest.raises(ParameterError) as flag:
        get_backend("soft").simulate(ti.load_scenario("open-center"), restitution=1.5)
    assert str(flag.value) == str(field.value).replace("contact.restitution", "--restitution")


def test_a_record_of_a_run_identifies_its_tree():
    """identify takes a Record and the test (a Scenario or a Pendulum with the trunk's
    geometry); the record of the exact model at 5 kHz, no noise, gives M_T back."""
    tree = ti.load_scenario("central-leader")
    run = ti.simulate(tree)
    record = ti.record_from_simulation(run)
    assert isinstance(record, ti.Record) and record.t[1] - record.t[0] == pytest.approx(2e-4)
    fit = ti.identify(record, tree)
    assert isinstance(fit, ti.Identification) and isinstance(fit.M_T, ti.Estimate)
    assert fit.explained and fit.M_T.unit == "kg"
    assert fit.M_T.value == pytest.approx(run.model.M_T, rel=1e-3)  # exact record: 0.1 %
    again = ti.identify(record, tree.impactor, clamp_height=tree.trunk.clamp_height,
                        diameter=tree.trunk.diameter)
    assert again.M_T.value == fit.M_T.value  # the same test, given in pieces


def test_the_release_angle_is_in_degrees_everywhere():
    pend = ti.Pendulum(mass=132.4, equivalent_length=1.51, release_angle_deg=36.39)
    assert pend.release_angle_rad == pytest.approx(math.radians(36.39), rel=1e-15)
    assert pend.impact_speed == pytest.approx(
        2 * math.sqrt(9.81 * 1.51) * math.sin(math.radians(36.39) / 2), rel=1e-15)  # eq 48
    assert ti.load_scenario("central-leader").impactor.release_angle_deg == 36.39
    with pytest.raises(TypeError):
        ti.Pendulum(mass=132.4, equivalent_length=1.51, release_angle=0.635)


#: README's own tree (the ``scenario`` command's example), as the API's keywords.
MY_TREE = dict(clamp_height=0.315, diameter=0.126, impactor_mass=132.4, equivalent_length=1.51,
               release_angle_deg=36.39, youngs_modulus=9e9, dynamic_mass=110.0,
               equivalent_stiffness=1.5e6, damping_rate=29.835)


def test_tree_scenario_is_the_scenario_command_s(tmp_path, capsys):
    """The API's tree_scenario and ``treeimpact scenario`` with the same inputs give the
    same file (one builder, compare.tree.scenario), and it reduces to the M_T, K_T given."""
    from treeimpact.analytic.model.reduction import reduce_trunk
    from treeimpact.compare.interface.cli import main

    argv = ["scenario", "my-tree", *[a for k, v in MY_TREE.items()
                                     for a in (f"--{k.replace('_', '-')}", repr(v))]]
    assert main(argv) == 0
    scen = ti.tree_scenario("my-tree", **MY_TREE)
    assert capsys.readouterr().out == ti.scenario_toml(scen)
    red = reduce_trunk(scen.trunk)
    assert red.dynamic_mass == pytest.approx(110.0, rel=1e-12)  # calibrated exactly (eq 7)
    assert red.equivalent_stiffness == pytest.approx(1.5e6, rel=1e-12)  # (eq 8)


@pytest.mark.parametrize("call, words", [
    (lambda: ti.simulate("open-center", backend="beam", element=8),
     ["element: not an option of backend 'beam'", "did you mean elements?"]),
    (lambda: ti.simulate("open-center", t_end=-1.0), ["t_end = -1.0 s is out of range"]),
    (lambda: ti.simulate("open-center", backend="mujoco", segments=1),
     ["segments = 1 is out of range: allowed [2, 1000]"]),
    (lambda: ti.record_from_simulation(ti.simulate("open-center"), rate_hz=1),
     ["rate_hz = 1 Hz is out of range"]),
    (lambda: ti.identify("no-such.csv", ti.load_scenario("open-center").impactor),
     ["clamp_height: required with a Pendulum"]),
    (lambda: ti.tree_scenario("t", **{**MY_TREE, "damping_rate": None}),
     ["damping_rate: missing (give b in 1/s, or a1 and a2)"]),
    (lambda: ti.tree_scenario("t", **MY_TREE, dampin_rate=3.0),
     ["dampin_rate: not an input of tree_scenario", "did you mean damping_rate?"]),
    (lambda: ti.tree_scenario("t", **{k: v for k, v in MY_TREE.items()
                                      if k != "impactor_mass"}, mass=20.0),
     ["mass: not an input of tree_scenario", "mass was renamed: did you mean impactor_mass?"]),
    (lambda: ti.tree_scenario("t", **{**MY_TREE, "x_max": 0.01}),
     ["equivalent_stiffness: give it or x_max and tau, not both"]),
])
def test_errors_from_the_api_name_keyword_arguments_not_flags(call, words):
    with pytest.raises(ti.ParameterError) as info:
        call()
    text = str(info.value)
    assert "--" not in text, text
    for w in words:
        assert w in text, text


def test_the_api_s_defaults_are_the_command_line_s():
    from treeimpact.compare.interface.cli import build_parser

    sub = build_parser()._subparsers._group_actions[0].choices
    default = {c: {a.dest: a.default for a in sub[c]._actions} for c in sub}
    assert tuple(default["sweep"]["backend"].split(",")) == SWEEP_BACKENDS == tuple(
        ti.backends())
    assert default["sweep"]["scenario"] == SWEEP_SCENARIO
    assert default["report"]["out"] == REPORT_DIR
    sig = {f.__name__: inspect.signature(f).parameters for f in FUNCTIONS}
    assert sig["sweep"]["backends"].default == SWEEP_BACKENDS
    assert sig["sweep"]["scenario"].default == SWEEP_SCENARIO
    assert sig["study"]["scenario"].default == SWEEP_SCENARIO  # sweep --preset's tree too
    assert sig["study"]["preset"].default == "default"
    assert sig["report"]["out"].default == REPORT_DIR
    assert sig["simulate"]["backend"].default == default["simulate"]["backend"]
    assert sig["modes"]["backend"].default == default["modes"]["backend"]
    assert sig["identify"]["restitution"].default is default["identify"]["restitution"]
    from treeimpact.compare.runs.recording import DEFAULTS

    assert sig["record_from_simulation"]["rate_hz"].default == DEFAULTS["rate"]
    assert sig["record_from_simulation"]["noise"].default == DEFAULTS["noise"]
    assert sig["record_from_simulation"]["seed"].default == DEFAULTS["seed"]


def test_report_runs_its_studies_beside_it_as_the_command_does(tmp_path):
    """treeimpact.report takes the command's --with-study (issue 51 item 3: the command calls
    it): a preset refused by its keyword as typed, as the command refuses it by its flag, and
    a Scenario object refused with it (a study's child process reads names or paths)."""
    with pytest.raises(ti.ParameterError, match=r"^with_study 'nope': allowed default"):
        ti.report(tmp_path, with_study=("nope",))
    with pytest.raises(ti.ParameterError, match="by shipped name or TOML path"):
        ti.report(tmp_path, [ti.load_scenario("open-center")], with_study=("default",))
    assert not any(tmp_path.iterdir())  # refused before anything was written
