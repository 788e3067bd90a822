"""The public API refuses bad keywords as the command line refuses bad flags (issue 54 item
7): a table of the fuzzer's cases for ``tree_scenario`` and ``design_map``, each a
ParameterError (a value out of range, missing, or not the form asked) or a TypeError (a
value of the wrong type) in one line that names the keyword as typed, never a private
class or a bare Python error. Every case is refused before anything runs (the design
map's ranges, types and the tree's keywords are checked where they enter)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import treeimpact as ti

#: README's own tree (the ``scenario`` command's example), as the API's keywords.
TREE = dict(clamp_height=0.315, diameter=0.126, impactor_mass=132.4, equivalent_length=1.51,
            release_angle_deg=36.39, youngs_modulus=9e9, dynamic_mass=110.0,
            equivalent_stiffness=1.5e6, damping_rate=29.835)
#: Names a message must not carry: the package's private classes, Python's own words.
PRIVATE = ("TreeInputs", "__init__", "positional argument", "Unknown format code",
           "unpack", "os.PathLike", "Traceback", "DesignRange", "SweepSpec", "Input(")


def _without(key):
    return {k: v for k, v in TREE.items() if k != key}


def _tree(**changes):
    return {**TREE, **changes}


def _elastic():
    """central-leader with an elastic pad, e = 1: a tree the Newton model runs."""
    import dataclasses

    scen = ti.load_scenario("central-leader")
    return dataclasses.replace(scen, contact=dataclasses.replace(scen.contact,
                                                                 restitution=1.0))


#: (keyword as typed, call, allowed error types).
TREE_CASES = [
    ("dynamic_mass", lambda: ti.tree_scenario("t", **_without("dynamic_mass")),
     ti.ParameterError),
    ("youngs_modulus", lambda: ti.tree_scenario("t", **_without("youngs_modulus")),
     ti.ParameterError),
    ("restitution", lambda: ti.tree_scenario("t", **_tree(restitution="1.0")), TypeError),
    ("damping_rate", lambda: ti.tree_scenario("t", **_tree(damping_rate=True)), TypeError),
    ("diameter", lambda: ti.tree_scenario("t", **_tree(diameter="0.126")), TypeError),
    ("t_end", lambda: ti.tree_scenario("t", **_tree(t_end=[0.1])), TypeError),
    ("clamp_mass", lambda: ti.tree_scenario("t", **_tree(clamp_mass=-1.0)), ti.ParameterError),
    ("restitution", lambda: ti.tree_scenario("t", **_tree(restitution=1.5)), ti.ParameterError),
    ("dynamic_mass", lambda: ti.tree_scenario("t", **_tree(dynamic_mass=math.nan)),
     ti.ParameterError),
    ("damping_rate", lambda: ti.tree_scenario("t", **_tree(damping_rate=math.inf)),
     ti.ParameterError),
    ("impactor_mass", lambda: ti.tree_scenario("t", **_tree(impactor_mass=1e5)),
     ti.ParameterError),
    ("name", lambda: ti.tree_scenario(3, **TREE), TypeError),
]
DESIGN_CASES = [
    ("ranges", lambda out: ti.design_map(out, ranges={"a_over_l": (0.1, 0.3, 0.5)}),
     ti.ParameterError),
    ("ranges", lambda out: ti.design_map(out, ranges={"a_over_l": "0.1-0.3"}),
     ti.ParameterError),
    ("ranges", lambda out: ti.design_map(out, ranges={"a_over_l": (0.1, "0.3")}),
     ti.ParameterError),
    ("ranges", lambda out: ti.design_map(out, ranges=[("a_over_l", (0.1, 0.3))]),
     ti.ParameterError),
    ("ranges", lambda out: ti.design_map(out, ranges={"clamp": (0.1, 0.3)}), ti.ParameterError),
    ("scenario", lambda out: ti.design_map(out, ti.Pendulum(mass=132.4, equivalent_length=1.51,
                                                            release_angle_deg=36.39)),
     TypeError),
    ("scenario", lambda out: ti.design_map(out, 5), TypeError),
    # e = 1 lies outside the study's allowed 0-0.95: refused by the tree's own value
    ("scenario", lambda out: ti.design_map(out, _elastic(), count=2, workers=0),
     ti.ParameterError),
    ("engines", lambda out: ti.design_map(out, engines="no"), TypeError),
    ("out", lambda out: ti.design_map(3), TypeError),
    ("count", lambda out: ti.design_map(out, count=2.0), ti.ParameterError),
]


@pytest.mark.parametrize("keyword, call, kinds", TREE_CASES,
                         ids=[f"tree_scenario-{i}-{c[0]}" for i, c in enumerate(TREE_CASES)])
def test_tree_scenario_refuses_a_bad_keyword_by_its_name(keyword, call, kinds):
    with pytest.raises(kinds) as info:
        call()
    _names_only(info.value, keyword)


@pytest.mark.parametrize("keyword, call, kinds", DESIGN_CASES,
                         ids=[f"design_map-{i}-{c[0]}" for i, c in enumerate(DESIGN_CASES)])
def test_design_map_refuses_a_bad_keyword_by_its_name(tmp_path, keyword, call, kinds):
    out = tmp_path / "d"
    with pytest.raises(kinds) as info:
        call(out)
    _names_only(info.value, keyword)
    assert not out.exists()  # refused before anything was written


def _names_only(exc, keyword: str) -> None:
    text = str(exc)
    assert type(exc) in (ti.ParameterError, TypeError), type(exc)
    assert "\n" not in text and text.startswith(keyword), text
    assert "--" not in text, text  # the keyword, not the command's flag
    assert not [p for p in PRIVATE if p in text], text


def test_a_missing_input_names_every_required_one():
    with pytest.raises(ti.ParameterError) as info:
        ti.tree_scenario("t", **_without("dynamic_mass"))
    text = str(info.value)
    assert text.startswith("dynamic_mass: missing (a number in kg)")
    for name in ("clamp_height", "diameter", "impactor_mass", "equivalent_length",
                 "release_angle_deg", "youngs_modulus"):
        assert name in text


def test_the_range_refused_is_the_registrys():
    from treeimpact.analytic.model.registry import BY_NAME

    p = BY_NAME["impactor_mass"]
    with pytest.raises(ti.ParameterError) as info:
        ti.tree_scenario("t", **_tree(impactor_mass=2 * p.high))
    assert f"allowed [{p.low:g}, {p.high:g}] kg" in str(info.value)


def test_numpy_numbers_are_numbers_and_give_the_same_tree():
    """A value from a numpy array is a number (the check is numbers.Real, not float)."""
    plain = ti.tree_scenario("t", **TREE)
    from_numpy = ti.tree_scenario("t", **{k: np.float64(v) for k, v in TREE.items()})
    assert ti.scenario_toml(plain) == ti.scenario_toml(from_numpy)


def test_values_the_registry_allows_are_kept_as_the_command_line_keeps_them():
    """b = 0 (an undamped tree), m_c = 0 (no clamp mass) and e = 1 lie in the registry's
    ranges and ``treeimpact scenario`` accepts them: so does the API (no second range)."""
    for changes in ({"damping_rate": 0.0}, {"clamp_mass": 0.0}, {"restitution": 1}):
        scen = ti.tree_scenario("t", **_tree(**changes))
        assert scen.name == "t"
