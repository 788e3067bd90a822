"""The parameter registry (analytic.model.registry): its paths exist, its units speak one
vocabulary, LIMITS is a view of it, its apply functions set what they say (closed forms),
and the places that name a physical input spell it as the registry does."""

from __future__ import annotations

import dataclasses
import math

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model import registry
from treeimpact.analytic.model.parameters import LIMITS, Contact, Pendulum, Trunk
from treeimpact.analytic.model.ratios import RATIOS, apply_input
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.scenario import load_scenario

#: The units the registry may use: SI, "1" for dimensionless (never "-" or "").
UNITS = {"m", "kg", "kg/m^3", "Pa", "N s/m^2", "N m/rad", "1", "deg", "m/s^2", "m/s", "N/m",
         "s", "N s/m", "log10 s", "1/s"}


def _central():
    return load_scenario("central-leader")


def test_names_paths_and_sweeps_are_unique():
    for key in ("name", "path", "sweep"):
        seen = [getattr(p, key) for p in registry.PARAMETERS if getattr(p, key) is not None]
        assert len(seen) == len(set(seen)), key


def test_units_one_vocabulary():
    assert {p.unit for p in registry.PARAMETERS} <= UNITS
    assert all(p.low <= p.high for p in registry.PARAMETERS)


def test_every_path_is_a_field_of_its_part():
    parts = {"trunk": {Trunk}, "impactor": {Pendulum}, "contact": {Contact}}
    for p in registry.PARAMETERS:
        if p.path is None or "." not in p.path:
            continue
        section, field = p.path.split(".")
        names = set().union(*({f.name for f in dataclasses.fields(c)} for c in parts[section]))
        assert field in names or hasattr(Pendulum, field), p.path


def test_limits_is_the_registry_view():
    assert LIMITS == {p.path: (p.low, p.high, p.unit) for p in registry.PARAMETERS if p.path}
    # the values LIMITS had before the registry (spot checks of each section)
    assert LIMITS["contact.restitution"] == (0.0, 1.0, "1")
    assert LIMITS["trunk.base_stiffness"] == (10.0, math.inf, "N m/rad")
    assert LIMITS["t_end"] == (1e-4, 10.0, "s")


def test_field_apply_sets_only_its_field():
    s = _central()
    for p in registry.PARAMETERS:
        if p.path is None or p.path in ("impactor.impact_speed", "impactor.release_angle_deg",
                                        "impactor.stiffness",  # a billet's, not the pendulum's
                                        "contact.stiffness", "contact.duration"):
            continue  # the exclusive pairs are checked below
        section, _, field = p.path.rpartition(".")
        now = getattr(getattr(s, section) if section else s, field)
        # 1 % off the file's value (keeps a <= l), the low end where the file has none or inf
        value = p.low if now is None or math.isinf(now) else 1.01 * now
        out = p.apply(s, value)
        assert getattr(getattr(out, section) if section else out, field) == value, p.name


def test_contact_stiffness_and_duration_exclude_each_other():
    s = _central()
    out = registry.BY_NAME["contact_stiffness"].apply(s, 1e5)
    assert (out.contact.stiffness, out.contact.duration) == (1e5, None)
    out = registry.BY_NAME["contact_duration"].apply(s, 2e-3)
    assert (out.contact.stiffness, out.contact.duration) == (None, 2e-3)


def test_ratio_apply_closed_forms():
    s = _central()
    t = s.trunk
    assert apply_input(s, "a_over_l", 0.25).trunk.clamp_height == 0.25 * t.length
    assert apply_input(s, "crown_ratio", 2.0).trunk.crown_mass == 2.0 * t.trunk_mass
    out = apply_input(s, "mass_ratio", 1.5)
    # m / M_T read back from the new scenario; M_T does not depend on m (eq 7)
    assert out.impactor.mass / reduce_trunk(out.trunk).dynamic_mass == pytest.approx(1.5, rel=1e-15)  # one rounding


def test_ratios_are_the_sweeps_derived_ratios():
    from treeimpact.compare.studies.sweep.grid import DERIVED_RATIOS

    assert set(RATIOS) == set(DERIVED_RATIOS)
    for name, (target, _) in DERIVED_RATIOS.items():
        assert registry.BY_NAME[name].sets == target


def test_design_ranges_inside_allowed_and_limits():
    for p in registry.PARAMETERS:
        if p.design is None:
            continue
        lo, hi = p.design.allowed
        assert lo <= p.design.low < p.design.high <= hi, p.name
        assert p.low <= lo and hi <= p.high, p.name


def test_lookup_by_name_path_or_sweep():
    assert registry.parameter("contact.duration") is registry.BY_NAME["contact_duration"]
    assert registry.parameter("trunk.crown_mass") is registry.BY_NAME["crown_mass"]
    with pytest.raises(ParameterError, match="not a parameter"):
        registry.parameter("stiffness")


def _scenario_options():
    """(option name, Option) of every backend option that overrides a scenario input."""
    from treeimpact.analytic.model import options
    from treeimpact.compare.runs.backends import BACKENDS

    shared = {id(o) for o in (options.RESTITUTION, options.T_END, options.CONTACT_STIFFNESS,
                              options.CONTACT_DURATION)}
    out = []
    for backend in BACKENDS.values():
        try:
            table = backend.options()
        except ParameterError:  # a backend not installed here
            continue
        out += [(n, o) for n, o in table.items() if id(o) in shared]
    return out


def test_every_place_spells_inputs_as_the_registry():
    """CLI options, sweep axes, map axes, the sensitivity and design studies' inputs: each
    physical input under the registry's name and in its unit."""
    from treeimpact.compare.studies import design
    from treeimpact.compare.studies import study_inputs as sensitivity
    from treeimpact.compare.studies.sweep.grid import ALIASES
    from treeimpact.compare.studies.sweep.map_cells import _AXES

    found = _scenario_options()
    assert {n for n, _ in found} == {"restitution", "t_end", "contact_stiffness",
                                     "contact_duration"}
    for name, option in found:  # the CLI flag --NAME and the sweep axis NAME
        p = registry.BY_SWEEP[name]
        assert (option.unit, option.low) == (p.unit, p.low), name
    for short, path in ALIASES.items():
        assert registry.BY_SWEEP[short].path == path
    for name, (_, factor, unit) in _AXES.items():
        if name in ("segments", "dt"):  # engine options, not physical inputs
            continue
        p = registry.BY_SWEEP[name]
        assert (factor, unit) == (p.shown[0], p.shown_unit), name
    for name, row in sensitivity.ALL_INPUTS.items():
        p = registry.BY_NAME[name]
        u = p.unmeasured
        assert row == (u.low, u.high, p.unit, u.why, u.measure), name
        assert p.low <= u.low < u.high <= p.high, name  # a study range inside the allowed one
    assert set(sensitivity.ALL_INPUTS) == {p.name for p in registry.PARAMETERS if p.unmeasured}
    for name, fields in sensitivity.FIELDS.items():
        assert all(f in registry.BY_PATH for f in fields), name
    for name, inp in design.INPUTS.items():
        p = registry.BY_NAME[name]
        assert (inp.unit, inp.low, inp.high, inp.allowed) == (
            p.unit, p.design.low, p.design.high, p.design.allowed), name


def test_model_fields_are_registry_names():
    """The reduced model's fields (TreeSDOF, TwoBodyModel, MeasuredTree) are spelled as the
    registry names their quantities (K_T is ``equivalent_stiffness`` everywhere in code, not
    ``stiffness``), and their comments give the registry's symbol and unit."""
    import inspect

    from treeimpact.analytic.model.calibration import MeasuredTree
    from treeimpact.analytic.model.reduction import TreeSDOF
    from treeimpact.analytic.model.two_body import TwoBodyModel

    for cls in (TreeSDOF, TwoBodyModel, MeasuredTree):
        source = inspect.getsource(cls)
        for f in dataclasses.fields(cls):
            p = registry.BY_NAME[f.name]  # KeyError: a field the registry does not name
            line = next(ln for ln in source.splitlines()
                        if ln.strip().startswith(f"{f.name}: float"))
            comment = line.split("#", 1)[1]
            assert comment.split(",")[0].split(":")[0].split(" = ")[0].strip() == p.symbol, (
                cls.__name__, f.name)
            assert p.unit in comment or p.unit == "1", (cls.__name__, f.name)


def test_report_input_keys_are_registry_names():
    """The JSON keys the report writes for the sensitivity study's inputs are registry
    names (compare.report.base reads their units and labels by these keys)."""
    from treeimpact.compare.studies.sweep.sensitivity_figure import INPUT_LABELS

    assert set(INPUT_LABELS) <= set(registry.BY_NAME)
    assert INPUT_LABELS["log10_pad_duration"] == "pad contact\nduration"  # not 'stiffness'


def test_the_docs_table_is_the_registry_s():
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "parameters.md").read_text()
    assert registry.registry_table() in page
    assert registry.assumed_table() in page  # a tree from its geometry's assumptions


def test_unit_tables_agree_with_the_registry():
    """Every unit table that names a registry quantity (by name or symbol: K_T, M_T, C_T,
    E, restitution) gives the registry's unit, and "1" (never "-") for a dimensionless one."""
    from treeimpact.analytic.identify.intervals import UNITS as FIT
    from treeimpact.compare.interface.api_results import ESTIMATE_UNITS
    from treeimpact.compare.interface.commands.simulate import MODEL_UNITS
    from treeimpact.compare.report.paper import UNITS as PAPER

    for table in (FIT, ESTIMATE_UNITS, MODEL_UNITS, PAPER):
        assert "-" not in table.values()
        for key, unit in table.items():
            if key in registry.BY_NAME or key in registry.BY_SYMBOL:
                assert unit == registry.units_of(key)[key], key
    with pytest.raises(KeyError):
        registry.units_of("k_t")


def test_small_e_sweep_passes_values_not_text():
    """The small-e sweep's grid holds the e values themselves (issue 42 item 3), the same
    grid the spec text it used to write parsed to; a bad value is refused."""
    from treeimpact.analytic.errors import ParameterError
    from treeimpact.compare.studies.small_e import grid_of, small_e_sweep
    from treeimpact.compare.studies.sweep.grid import parse_grid, value_axis

    s = _central()
    grid = small_e_sweep(s, "unused").grid
    assert grid.axes[0].values == grid_of(s)
    assert grid == parse_grid(["restitution=" + ",".join(repr(e) for e in grid_of(s))])
    with pytest.raises(ParameterError):
        value_axis("restitution", (0.1, float("nan")))
